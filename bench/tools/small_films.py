#!/usr/bin/env python3
"""Summarises bench/run_small_films.sh's CSV: per film size, B's render time over A's per round
at 1 thread and at N threads (median [range]), and each build's scaling, its 1-thread time
over its N-thread time in the same round. Writes a plot of the scaling next to the CSV.

    bench/tools/small_films.py RUNS_CSV
"""
import sys

from ab_summary import median_range as fmt, plot_builds, read_runs


def main():
    path, rows = read_runs(__doc__)
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

    plot_builds(path.with_suffix(".png"), [f"{r}×{r}" for r in sizes],
                {(i, b): scaling[(res, b)] for i, res in enumerate(sizes) for b in ("A", "B")},
                f"1-thread time / {n}-thread time", n, f"ideal ({n})", ":", (6, 3.5),
                legend_size=8, grid=True)

if __name__ == "__main__":
    main()
