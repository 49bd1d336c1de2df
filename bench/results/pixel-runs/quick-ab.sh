#!/bin/bash
# Quick A/B of the transient film's cost: per round, each build (the order swapped every round)
# renders the Cornell box (experiments/scenes/cornell-films.xml, 128x128, box filter) with
# `path` into an hdrfilm and `transient_path` into the 1024-bin film. Prints
# "ROUND a|b INTEGRATOR SECONDS" per render (the render time `femto render` reports).
#   quick-ab.sh A_PREFIX B_PREFIX ROUNDS THREADS [SPP=64] > OUT.txt
#   bench/tools/film_ab_summary.py --quick OUT.txt
a=$1 b=$2 n=$3 t=$4 spp=${5:-64}
scene=$(cd "$(dirname "$0")/../../experiments/scenes" && pwd)/cornell-films.xml
out=$(mktemp -d); trap 'rm -rf "$out"' EXIT
for r in $(seq "$n"); do
  order="a b"; (( r % 2 == 0 )) && order="b a"
  for v in $order; do
    p=$a; [[ $v == b ]] && p=$b
    for f in "path hdrfilm" "transient_path transient"; do
      set -- $f
      s=$("$p/bin/femto" render "$scene" -D integrator=$1 -D film=$2 -D res=128 --spp "$spp" \
          --threads "$t" -o "$out/q" 2>&1 | grep -oE "in [0-9.]+ s \(" | grep -oE "[0-9.]+")
      echo "$r $v $1 $s"
    done
  done
done
