#!/usr/bin/env python3
"""Samples per second of each variant over a baseline variant's, run by run, from the
compare_runs.csv that bench/run_compare.sh writes: for each build (before, after), the ratio of
variant V to BASELINE in the same round and seed, then the median and the 5 % / 95 % quantiles
over all pairs. Used for issue 17's transient-film goal (experiments/transient-throughput.xml).

    bench/tools/film_ratio.py RUNS_CSV [BASELINE]      (BASELINE: path-hdrfilm)
"""
import csv
import statistics
import sys


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    baseline = sys.argv[2] if len(sys.argv) > 2 else "path-hdrfilm"
    rate = {}
    with open(sys.argv[1], newline="") as f:
        for r in csv.DictReader(f):
            key = (r["build"], r["scene"], r["round"], r["seed"], r["variant"])
            rate[key] = float(r["samples"]) / float(r["seconds"])
    variants = sorted({k[4] for k in rate} - {baseline})
    print("build,scene,variant,pairs,median,q05,q95")
    for build in ("before", "after"):
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
