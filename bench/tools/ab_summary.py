"""What the two-build summaries (build_ab.py, small_films.py) share: reading their CSV, the
median [range] of a list of per-round values, and a plot of each build's per-round values per
category."""
import csv
import statistics
import sys
from pathlib import Path


def read_runs(usage):
    """The CSV named by the one command-line argument (else exits with `usage`): its path and
    its rows."""
    if len(sys.argv) != 2:
        sys.exit(usage)
    path = Path(sys.argv[1])
    with open(path, newline="") as f:
        return path, list(csv.DictReader(f))


def median_range(values):
    """'median [min, max]' to three decimals."""
    return f"{statistics.median(values):.3f} [{min(values):.3f}, {max(values):.3f}]"


def plot_builds(png, labels, values, ylabel, line, line_label, line_style, figsize,
                legend_size=None, grid=False):
    """Writes `png`: one dot per round, values[(i, build)] for category i (x axis, labelled
    `labels`) and build "A" or "B" side by side, and a horizontal line at `line` (a goal, an
    ideal). Says so and writes nothing when matplotlib is missing."""
    try:
        import matplotlib
    except ImportError:
        print("(matplotlib is missing: no plot)", file=sys.stderr)
        return
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=figsize)
    for bi, b in enumerate(("A", "B")):
        for i in range(len(labels)):
            y = values[(i, b)]
            ax.plot([i + (bi - 0.5) * 0.3] * len(y), y, "o", color=f"C{bi}", alpha=0.6,
                    label=f"build {b}" if i == 0 else None)
    ax.axhline(line, color="gray", ls=line_style, label=line_label)
    ax.set_xticks(range(len(labels)))
    ax.set_xticklabels(labels)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize=legend_size)
    if grid:
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=100)
