#!/bin/bash
# Quick A/B of two builds' render time: path on the Cornell box (experiments/scenes/cornell-films.xml,
# hdrfilm, 256x256, 16 spp), ROUNDS rounds alternating A and B, at THREADS threads. Prints
# "ROUND a|b in SECONDS s (MRAYS M rays" per render.
#   bench/run_quick_ab.sh A_PREFIX B_PREFIX ROUNDS THREADS [femto render args...] > OUT.txt
#   bench/tools/quick_ab_summary.py OUT.txt
# (A_PREFIX/bin/femto and B_PREFIX/bin/femto: a build folder or a `cmake --install` prefix.)
a=$1 b=$2 n=$3 t=$4; shift 4
repo=$(cd "$(dirname "$0")/.." && pwd)
out=$(mktemp -d); trap 'rm -rf "$out"' EXIT
for r in $(seq "$n"); do
  for v in a b; do
    p=$a; [[ $v == b ]] && p=$b
    s=$("$p/bin/femto" render "$repo/bench/experiments/scenes/cornell-films.xml" -D integrator=path \
        -D film=hdrfilm -D res=256 --spp 16 --threads "$t" -o "$out/q" "$@" 2>&1 |
        grep -oE "in [0-9.]+ s \([0-9.]+ M rays" | tr "\n" " ")
    echo "$r $v $s"
  done
done
