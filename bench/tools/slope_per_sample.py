#!/usr/bin/env python3
"""Log-log slope of an error against samples per pixel (passes, for transient_ppm), per scene and
variant, from the results.csv of a `femto bench` study with spp budgets: a least-squares fit of
log(error) on log(spp) over every run, with its 95 % interval (Student's t). `femto bench`'s own
report fits error against time; a consistent estimator's rate (appendix 5.B: n^-4/7) is a rate
in passes, which this gives without the machine's speed in it. Used for issue 14's slope
(experiments/ppm-slope.xml, bench/README.md).

    bench/tools/slope_per_sample.py RESULTS_CSV [METRIC ...]     (METRIC: relmse, the default)
"""
import csv
import sys

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


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    metrics = sys.argv[2:] or ["relmse"]
    with open(sys.argv[1], newline="") as f:
        rows = list(csv.DictReader(f))
    groups = {}
    for r in rows:
        groups.setdefault((r["scene"], r["variant"]), []).append(r)
    print("scene,variant,metric,runs,slope,ci95")
    for (scene, variant), runs in groups.items():
        for metric in metrics:
            pairs = [(float(r["spp"]), float(r[metric])) for r in runs]
            pairs = [(n, e) for n, e in pairs if e > 0 and np.isfinite(e)]
            if len(pairs) < 3:
                continue
            slope, ci = fit(*map(np.array, zip(*pairs)))
            print(f"{scene},{variant},{metric},{len(pairs)},{slope:.3f},{ci:.3f}")


if __name__ == "__main__":
    main()
