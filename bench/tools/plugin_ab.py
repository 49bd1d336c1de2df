#!/usr/bin/env python3
"""Summary of a side-by-side run of two builds of a plugin and the path tracer: per round, the new
build's time over the old one's, and each build's rays per second over the path tracer's of the
same round, as median [min, max] over the rounds. Used for the BDPT ray-rate changes in
bench/README.md (results/bdpt-in-place/, results/media-exp/).

    bench/tools/plugin_ab.py RUNS_CSV...

RUNS_CSV: `round,build,integrator,seconds,mrays` with build `old`, `new` and `path`, one row each
per round (the two plugin builds through `femto render ... --plugin-dir DIR`, alternated with the
path tracer in every round).
"""
import csv
import statistics
import sys


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for name in sys.argv[1:]:
        with open(name, newline="") as f:
            rate = {(r["round"], r["build"]): float(r["mrays"]) for r in csv.DictReader(f)}
        rounds = sorted({k for k, _ in rate}, key=int)
        time_ratio = [rate[(k, "old")] / rate[(k, "new")] for k in rounds]
        old = [rate[(k, "old")] / rate[(k, "path")] for k in rounds]
        new = [rate[(k, "new")] / rate[(k, "path")] for k in rounds]

        def show(xs):
            return f"{statistics.median(xs):.3f} [{min(xs):.3f}, {max(xs):.3f}]"

        print(f"{name}: time new/old {show(time_ratio)}; rays/s over the path tracer's: "
              f"old {show(old)}, new {show(new)}")


if __name__ == "__main__":
    main()
