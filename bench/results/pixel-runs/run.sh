#!/bin/bash
# The pixel-run trial's runs: `femto bench experiments/transient-throughput.xml` with build A and
# build B (a build folder or a `cmake --install` prefix each), 3 rounds at 1 and 2 threads, the
# builds' order swapped every round, into OUT/{A,B}-tTHREADS-rROUND. Then
# bench/results/pixel-runs/summarize.py OUT.
#   run.sh A B OUT
set -euo pipefail
a=$1 b=$2 out=$3
cd "$(dirname "$0")/../../.."   # the repository
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
