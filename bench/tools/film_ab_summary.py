#!/usr/bin/env python3
"""The transient film's cost in two builds, from bench/run_film_ab.sh's folder OUT
({A,B}-tT-rR/results.csv, or {A,B}-tT-rR.csv as kept in results/) or from the output of
results/pixel-runs/quick-ab.sh.

    film_ab_summary.py OUT
        per thread count and build, the 1024-bin film's samples/s over path-hdrfilm's (same
        seed and round, pooled over rounds: median [5 %, 95 %]), then each variant's render
        time B/A (same seed and round)
    film_ab_summary.py --quick FILE
        per build the round-by-round ratio of path's time over transient_path's, then each
        integrator's time B/A
"""
import collections
import csv
import statistics
import sys


def bench(folder):
    def load(build, t, r):
        name = f"{folder}/{build}-t{t}-r{r}"
        try:
            rows = list(csv.DictReader(open(name + "/results.csv")))
        except FileNotFoundError:
            rows = list(csv.DictReader(open(name + ".csv")))
        return {(x["seed"], x["variant"]): x for x in rows}

    for t in "12":
        for b in "AB":
            ratios = []
            for r in (1, 2, 3):
                rows = load(b, t, r)
                rate = {k: float(x["samples"]) / float(x["seconds"]) for k, x in rows.items()}
                ratios += [rate[(s, "transient_path-1024-bins")] / rate[(s, "path-hdrfilm")]
                           for s in {k[0] for k in rate}]
            ratios.sort()
            n = len(ratios)
            print(f"threads {t} build {b}: 1024-bin/hdrfilm median {statistics.median(ratios):.3f} "
                  f"[{ratios[int(0.05 * n)]:.3f}, {ratios[int(0.95 * n) - 1]:.3f}] n={n}")
    for t in "12":
        for v in ("path-hdrfilm", "transient_path-1024-bins", "transient_path-1-bin"):
            rs = []
            for r in (1, 2, 3):
                a, b = load("A", t, r), load("B", t, r)
                rs += [float(b[k]["seconds"]) / float(a[k]["seconds"]) for k in a
                       if k[1] == v and k in b]
            rs.sort()
            print(f"threads {t} {v}: time B/A median {statistics.median(rs):.3f} "
                  f"q25 {rs[len(rs) // 4]:.3f} q75 {rs[3 * len(rs) // 4]:.3f} n={len(rs)}")


def quick(path):
    d = collections.defaultdict(dict)
    for line in open(path):
        p = line.split()
        if len(p) == 4:
            d[(p[0], p[1])][p[2]] = float(p[3])
    rounds = sorted({k[0] for k in d}, key=int)
    for v in "ab":
        rat = [d[(r, v)]["path"] / d[(r, v)]["transient_path"] for r in rounds
               if len(d[(r, v)]) == 2]
        print(f"{v}: path time / transient_path time median {statistics.median(rat):.3f} "
              f"min {min(rat):.3f} max {max(rat):.3f} n={len(rat)}")
    for integ in ("path", "transient_path"):
        rr = [d[(r, "b")][integ] / d[(r, "a")][integ] for r in rounds
              if integ in d[(r, "a")] and integ in d[(r, "b")]]
        print(f"{integ}: time b/a median {statistics.median(rr):.3f} min {min(rr):.3f} "
              f"max {max(rr):.3f}")


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--quick":
        quick(sys.argv[2])
    elif len(sys.argv) == 2:
        bench(sys.argv[1])
    else:
        sys.exit(__doc__)
