#!/usr/bin/env python3
"""Samples per second of each variant over a baseline variant's, run by run, from the
compare_runs.csv that bench/run_compare.sh writes: for each build (before, after), the ratio of
variant V to BASELINE in the same round and seed, then the median and the 5 % / 95 % quantiles
over all pairs. Used for issue 17's transient-film goal (experiments/transient-throughput.xml).

    bench/tools/film_ratio.py RUNS_CSV [BASELINE]      (BASELINE: path-hdrfilm)

It also reads `femto bench` results.csv files (no build or round column): each file is then a
build of its own, named by the file, and a round of it; several such files may be given:

    bench/tools/film_ratio.py OUT-1/results.csv OUT-2/results.csv ...
"""
import csv
import statistics
import sys


def main():
    args = sys.argv[1:]
    if not args:
        sys.exit(__doc__)
    baseline = "path-hdrfilm"
    if len(args) == 2 and not args[1].endswith(".csv"):
        baseline = args.pop()
    rate = {}
    builds = []
    for path in args:
        with open(path, newline="") as f:
            for r in csv.DictReader(f):
                build = r.get("build", path)
                if build not in builds:
                    builds.append(build)
                key = (build, r["scene"], r.get("round", "1"), r["seed"], r["variant"])
                rate[key] = float(r["samples"]) / float(r["seconds"])
    variants = sorted({k[4] for k in rate} - {baseline})
    print("build,scene,variant,pairs,median,q05,q95")
    for build in builds:
        for scene in sorted({k[1] for k in rate}):
            for v in variants:
                ratios = sorted(
                    x / rate[(b, s, ro, se, baseline)]
                    for (b, s, ro, se, vv), x in rate.items()
                    if b == build and s == scene and vv == v and (b, s, ro, se, baseline) in rate)
                if not ratios:
                    continue
                n = len(ratios)
                q = lambda p: ratios[min(n - 1, round(p * (n - 1)))]
                print(f"{build},{scene},{v},{n},{statistics.median(ratios):.3f},"
                      f"{q(0.05):.3f},{q(0.95):.3f}")


if __name__ == "__main__":
    main()
