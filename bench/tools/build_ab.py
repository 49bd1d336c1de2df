#!/usr/bin/env python3
"""Summarises bench/run_build_ab.sh's CSV: per scene, B's render time over A's per round
(median [range]) for each integrator, and each build's transient_bdpt / transient_path rays
per second per round (issue 11's ratio). Writes a plot of the ratios next to the CSV.

    bench/tools/build_ab.py RUNS_CSV
"""

from ab_summary import median_range as fmt, plot_builds, read_runs


def main():
    path, rows = read_runs(__doc__)
    seconds = {(r["round"], r["build"], r["scene"], r["integrator"]): float(r["seconds"])
               for r in rows}
    rate = {(r["round"], r["build"], r["scene"], r["integrator"]): float(r["mrays"])
            for r in rows}
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    rounds = sorted({r["round"] for r in rows}, key=int)

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

    plot_builds(path.with_suffix(".png"), scenes,
                {(i, b): ratios[(scene, b)] for i, scene in enumerate(scenes) for b in ("A", "B")},
                "transient_bdpt / transient_path rays/s", 0.8, "issue 11's goal", "--", (7, 4))

if __name__ == "__main__":
    main()
