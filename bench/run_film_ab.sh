#!/bin/bash
# The transient film's cost in two builds, side by side: `femto bench
# experiments/transient-throughput.xml` with build A and build B (a build folder or a
# `cmake --install` prefix each), 3 rounds at 1 and 2 threads, the builds' order swapped every
# round, into OUT/{A,B}-tTHREADS-rROUND. Then bench/tools/film_ab_summary.py OUT, or
# bench/tools/film_ratio.py OUT/A-t1-r*/results.csv OUT/B-t1-r*/results.csv (and t2).
# (The cube-prefetch and pixel-run trials' runs: results/cube-prefetch/, results/pixel-runs/.)
#   bench/run_film_ab.sh A B OUT
set -euo pipefail
a=$(realpath "$1") b=$(realpath "$2") out=$(realpath -m "$3")
cd "$(dirname "$0")/.."   # the repository
mkdir -p "$out"
for r in 1 2 3; do
  for t in 1 2; do
    order="A B"; (( r % 2 == 0 )) && order="B A"
    for v in $order; do
      p=$a; [[ $v == B ]] && p=$b
      dir=$out/$v-t$t-r$r; rm -rf "$dir"   # femto bench reuses a folder's cached runs
      "$p/bin/femto" bench bench/experiments/transient-throughput.xml --threads "$t" -o "$dir" \
          > "$dir.log" 2>&1
    done
  done
done
echo DONE
