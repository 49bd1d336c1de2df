#!/usr/bin/env python3
"""Summarises bench/run_build_ab.sh's CSV: per scene, B's render time over A's per round
(median [range]) for each integrator, and each build's transient_bdpt / transient_path rays
per second per round (issue 11's ratio). Writes a plot of the ratios next to the CSV.

    bench/tools/build_ab.py RUNS_CSV
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
    seconds = {(r["round"], r["build"], r["scene"], r["integrator"]): float(r["seconds"])
               for r in rows}
    rate = {(r["round"], r["build"], r["scene"], r["integrator"]): float(r["mrays"])
            for r in rows}
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    rounds = sorted({r["round"] for r in rows}, key=int)

    def fmt(values):
        return f"{statistics.median(values):.3f} [{min(values):.3f}, {max(values):.3f}]"

    print("| scene | path time B / A | BDPT time B / A | BDPT / path rays/s, A | B |")
    print("|---|---|---|---|---|")
    ratios = {}
    for scene in scenes:
        times = {i: [seconds[(k, "B", scene, i)] / seconds[(k, "A", scene, i)] for k in rounds]
                 for i in ("transient_path", "transient_bdpt")}
        for b in ("A", "B"):
            ratios[(scene, b)] = [rate[(k, b, scene, "transient_bdpt")] /
                                  rate[(k, b, scene, "transient_path")] for k in rounds]
        print(f"| {scene} | {fmt(times['transient_path'])} | {fmt(times['transient_bdpt'])} "
              f"| {fmt(ratios[(scene, 'A')])} | {fmt(ratios[(scene, 'B')])} |")

    try:
        import matplotlib
    except ImportError:
        print("(matplotlib is missing: no plot)", file=sys.stderr)
        return
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4))
    for bi, b in enumerate(("A", "B")):
        for si, scene in enumerate(scenes):
            y = ratios[(scene, b)]
            ax.plot([si + (bi - 0.5) * 0.3] * len(y), y, "o", color=f"C{bi}", alpha=0.6,
                    label=f"build {b}" if si == 0 else None)
    ax.axhline(0.8, color="gray", ls="--", label="issue 11's goal")
    ax.set_xticks(range(len(scenes)))
    ax.set_xticklabels(scenes)
    ax.set_ylabel("transient_bdpt / transient_path rays/s")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path.with_suffix(".png"), dpi=100)


if __name__ == "__main__":
    main()
