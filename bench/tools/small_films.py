#!/usr/bin/env python3
"""Summarises bench/run_small_films.sh's CSV: per film size, B's render time over A's per round
at 1 thread and at N threads (median [range]), and each build's scaling, its 1-thread time
over its N-thread time in the same round. Writes a plot of the scaling next to the CSV.

    bench/tools/small_films.py RUNS_CSV
"""
import csv
import statistics
import sys
from pathlib import Path


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    path = Path(sys.argv[1])
    rows = list(csv.DictReader(open(path)))
    seconds = {(r["round"], r["build"], int(r["res"]), int(r["threads"])): float(r["seconds"])
               for r in rows}
    sizes = sorted({int(r["res"]) for r in rows})
    n = max((int(r["threads"]) for r in rows), default=1)
    if n < 2:
        sys.exit(f"{path}: no rows of more than one thread to compare with one")
    # Rounds with every render (an interrupted run leaves its last one partial).
    rounds = sorted({r["round"] for r in rows if all(
        (r["round"], b, res, t) in seconds for b in "AB" for res in sizes for t in (1, n))},
        key=int)
    if not rounds:
        sys.exit(f"{path}: no complete round")

    def fmt(values):
        return f"{statistics.median(values):.3f} [{min(values):.3f}, {max(values):.3f}]"

    print(f"| film | time B / A, 1 thread | time B / A, {n} threads "
          f"| scaling A (1 → {n} threads) | scaling B |")
    print("|---|---|---|---|---|")
    scaling = {}
    for res in sizes:
        times = {t: [seconds[(k, "B", res, t)] / seconds[(k, "A", res, t)] for k in rounds]
                 for t in (1, n)}
        for b in ("A", "B"):
            scaling[(res, b)] = [seconds[(k, b, res, 1)] / seconds[(k, b, res, n)]
                                 for k in rounds]
        print(f"| {res}×{res} | {fmt(times[1])} | {fmt(times[n])} | {fmt(scaling[(res, 'A')])} "
              f"| {fmt(scaling[(res, 'B')])} |")

    try:
        import matplotlib
    except ImportError:
        print("(matplotlib is missing: no plot)", file=sys.stderr)
        return
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for bi, b in enumerate(("A", "B")):
        for si, res in enumerate(sizes):
            y = scaling[(res, b)]
            ax.plot([si + (bi - 0.5) * 0.3] * len(y), y, "o", color=f"C{bi}", alpha=0.6,
                    label=f"build {b}" if si == 0 else None)
    ax.axhline(n, color="gray", ls=":", label=f"ideal ({n})")
    ax.set_xticks(range(len(sizes)))
    ax.set_xticklabels([f"{r}×{r}" for r in sizes])
    ax.set_ylabel(f"1-thread time / {n}-thread time")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path.with_suffix(".png"), dpi=100)


if __name__ == "__main__":
    main()
