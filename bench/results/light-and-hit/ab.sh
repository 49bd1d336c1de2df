#!/bin/bash
# Whole-build A/B of the path tracer's ray rate (issue 17's yardstick, ray-rate-path.xml: the
# Cornell box and the 1M-triangle displaced sphere, 256x256, 8 spp, 3 seeds, Embree's raw rates
# measured before each seed). OLD and NEW are two build trees (each femto loads its own
# plugins); ROUNDS rounds at 1 and 2 threads, the builds' order swapped every round, into
# OUT/BUILD-tTHREADS-rROUND. ../ldsampler-batch/rate_ratio.py OUT gives the ratios.
#   ab.sh OLD_BUILD NEW_BUILD OUT [ROUNDS]
set -euo pipefail
old=$1 new=$2 out=$3 rounds=${4:-5}
cd "$(dirname "$0")/../../.."   # the repository
mkdir -p "$out"
for t in 1 2; do
    for r in $(seq "$rounds"); do
        order="old new"; (( r % 2 == 0 )) && order="new old"
        for v in $order; do
            b=$old; [[ $v == new ]] && b=$new
            "$b/bin/femto" bench bench/experiments/ray-rate-path.xml --threads "$t" \
                -o "$out/$v-t$t-r$r" > "$out/$v-t$t-r$r.log" 2>&1
        done
    done
done
echo DONE
