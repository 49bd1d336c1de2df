#!/usr/bin/env python3
"""Log-log slope of an error against samples per pixel (passes, for transient_ppm), per scene and
variant, from the results.csv of a `femto bench` study with spp budgets: a least-squares fit of
log(error) on log(spp) over every run, with its 95 % interval (Student's t). `femto bench`'s own
report fits error against time; a consistent estimator's rate (appendix 5.B: n^-4/7) is a rate
in passes, which this gives without the machine's speed in it. Used for issue 14's slope
(experiments/ppm-slope.xml, experiments/ppm-slope-long.xml, bench/README.md).

    bench/tools/slope_per_sample.py [--min-spp N] [--local] RESULTS_CSV [METRIC ...]

METRIC: relmse (the default), or any error column of results.csv.
--min-spp N: fit only the runs of N or more samples per pixel (an asymptotic rate is the slope
             where the error's terms have settled; say which range a quoted slope is over).
--local:     also print the local slope between each pair of consecutive budgets (from the
             medians over the seeds), which shows whether the slope is still changing.
"""
import argparse
import csv
import statistics

import numpy as np
from scipy import stats


def fit(spp, errors):
    x, y = np.log(spp), np.log(errors)
    a = np.vstack([x, np.ones_like(x)]).T
    coef, _, _, _ = np.linalg.lstsq(a, y, rcond=None)
    dof = len(x) - 2
    residual = y - a @ coef
    cov = (residual @ residual / dof) * np.linalg.inv(a.T @ a)
    return coef[0], stats.t.ppf(0.975, dof) * np.sqrt(cov[0, 0])


def local_slopes(pairs):
    """(budget, next budget, slope) between consecutive budgets' median errors."""
    by_budget = {}
    for n, e in pairs:
        by_budget.setdefault(n, []).append(e)
    budgets = sorted(by_budget)
    medians = [statistics.median(by_budget[n]) for n in budgets]
    return [(budgets[i], budgets[i + 1],
             np.log(medians[i + 1] / medians[i]) / np.log(budgets[i + 1] / budgets[i]))
            for i in range(len(budgets) - 1)]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--min-spp", type=float, default=0)
    parser.add_argument("--local", action="store_true")
    parser.add_argument("results")
    parser.add_argument("metrics", nargs="*", default=["relmse"])
    args = parser.parse_args()
    with open(args.results, newline="") as f:
        rows = list(csv.DictReader(f))
    groups = {}
    for r in rows:
        groups.setdefault((r["scene"], r["variant"]), []).append(r)
    print("scene,variant,metric,runs,min_spp,slope,ci95")
    local = []
    for (scene, variant), runs in groups.items():
        for metric in args.metrics:
            pairs = [(float(r["spp"]), float(r[metric])) for r in runs]
            pairs = [(n, e) for n, e in pairs if e > 0 and np.isfinite(e) and n >= args.min_spp]
            if len(pairs) < 3:
                continue
            slope, ci = fit(*map(np.array, zip(*pairs)))
            lowest = min(n for n, _ in pairs)
            print(f"{scene},{variant},{metric},{len(pairs)},{lowest:g},{slope:.3f},{ci:.3f}")
            local += [(scene, variant, metric, a, b, s) for a, b, s in local_slopes(pairs)]
    if args.local:
        print("\nscene,variant,metric,from_spp,to_spp,local_slope")
        for scene, variant, metric, a, b, s in local:
            print(f"{scene},{variant},{metric},{a:g},{b:g},{s:.3f}")


if __name__ == "__main__":
    main()
