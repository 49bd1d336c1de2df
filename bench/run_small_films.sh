#!/usr/bin/env bash
# Small films at 1 and at THREADS threads, two builds side by side: `path` into an hdrfilm on the
# Cornell box (bench/experiments/scenes/cornell-films.xml) at 32x32, 64x64, 128x128 and
# 256x256, with spp chosen so that each render takes about the same time (512, 128, 32, 8).
# A pass renders its tiles in parallel, so a film of few tiles leaves threads idle; this
# measures what the tile size does to that, and what smaller tiles cost a thread.
#
#     bench/run_small_films.sh OUT_CSV BUILD_A BUILD_B [ROUNDS] [THREADS]
#
# BUILD_A and BUILD_B are build folders (each with bin/femto and its plugins, as for
# run_build_ab.sh). Each round renders every film size at 1 thread and at THREADS (default 2)
# with both builds, the builds' order alternating from round to round. ROUNDS default 7.
# Rows `round,build,res,threads,seconds` go to OUT_CSV; tools/small_films.py OUT_CSV
# summarises them (per size and thread count, B's time over A's per round, and each build's
# scaling: its 1-thread time over its THREADS-thread time in the same round). About 20 s a
# round on 2 cores.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
two_builds_args 16 "$@"
out=$1 build_a=$2 build_b=$3 rounds=${4:-7} threads=${5:-2}

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
bench_log_header "$work/log" >&2
echo "cores used: 1 and $threads of $(nproc)" >&2
xml="$root/bench/experiments/scenes/cornell-films.xml"
sizes=("32|512" "64|128" "128|32" "256|8")  # res|spp
echo "round,build,res,threads,seconds" > "$out"
for round in $(seq 1 "$rounds"); do
    order=(A B)
    (( round % 2 == 0 )) && order=(B A)
    for entry in "${sizes[@]}"; do
        res=${entry%%|*} spp=${entry#*|}
        for name in "${order[@]}"; do
            dir=$([[ $name == A ]] && echo "$build_a" || echo "$build_b")
            for n in 1 "$threads"; do
                line=$("$dir/bin/femto" render "$xml" -D integrator=path -D film=hdrfilm \
                    -D res="$res" -D spp="$spp" --threads "$n" -o "$work/out" 2>&1 |
                    render_seconds_and_rate)
                read -r seconds _ <<< "$line"
                echo "$round,$name,$res,$n,$seconds" | tee -a "$out"
            done
        done
    done
done
echo "load average after the benchmark: $(cat /proc/loadavg)" >&2
