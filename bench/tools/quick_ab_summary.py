#!/usr/bin/env python3
"""Summary of bench/run_quick_ab.sh's output (lines "ROUND a|b in SECONDS s (MRAYS M rays"):
B's render time over A's in the same round (median and quartiles), then each build's fastest,
10th-percentile and median time (interference on a shared machine only adds time, so the
fastest runs are the steadiest comparison).

    bench/tools/quick_ab_summary.py OUT.txt
"""
import statistics
import sys


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    seconds = {}
    for line in open(sys.argv[1]):
        p = line.split()
        if len(p) >= 4 and p[2] == "in":
            seconds[(p[0], p[1])] = float(p[3])
    rounds = sorted({k[0] for k in seconds}, key=int)
    r = sorted(seconds[(x, "b")] / seconds[(x, "a")] for x in rounds
               if (x, "a") in seconds and (x, "b") in seconds)
    n = len(r)
    print(f"b/a time median {statistics.median(r):.4f} q25 {r[n // 4]:.4f} "
          f"q75 {r[3 * n // 4]:.4f} n={n}")
    for v in "ab":
        t = sorted(seconds[(x, v)] for x in rounds if (x, v) in seconds)
        print(f"{v}: min {t[0]:.3f} p10 {t[len(t) // 10]:.3f} median {statistics.median(t):.3f} s")


if __name__ == "__main__":
    main()
