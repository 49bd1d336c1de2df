#!/usr/bin/env bash
# Two whole builds (femto, libfemto and plugins) side by side on run_ray_rate.sh's scenes:
#
#     bench/run_build_ab.sh OUT_CSV BUILD_A BUILD_B [ROUNDS] [THREADS]
#
# BUILD_A and BUILD_B are build folders (each with bin/femto and its plugins; e.g. a worktree
# of the old revision built with `cmake -S OLD -B BUILD_A -G Ninja -DCMAKE_BUILD_TYPE=Release`).
# Each round renders cornell-box, fog-object and caustic with transient_path and
# transient_bdpt from both builds, the builds' order alternating from round to round (the
# second of two runs in a row is not always the same build: on a VM that alone moved times by a
# few per cent). ROUNDS default 10, THREADS 2. Rows `round,build,scene,integrator,seconds,mrays`
# go to OUT_CSV; tools/build_ab.py OUT_CSV summarises them (B's time over A's per round, and
# each build's BDPT / path rays/s, issue 11's ratio). About 25 s a round on 2 cores.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
two_builds_args 13 "$@"
out=$1 build_a=$2 build_b=$3 rounds=${4:-10} threads=${5:-2}

work=$(mktemp -d)
trap 'rm -rf "$work"; remove_scene_copies' EXIT
bench_log_header "$work/log" >&2
echo "round,build,scene,integrator,seconds,mrays" > "$out"
for round in $(seq 1 "$rounds"); do
    order=(A B)  # by name, not folder: the same folder twice measures the noise (an A/A run)
    (( round % 2 == 0 )) && order=(B A)
    for entry in "${ray_rate_scenes[@]}"; do
        scene=${entry%%|*}
        read -r -a defines <<< "${entry#*|}"
        for name in "${order[@]}"; do
            dir=$([[ $name == A ]] && echo "$build_a" || echo "$build_b")
            for integrator in transient_path transient_bdpt; do
                line=$(ray_rate_render "$dir/bin/femto" "$scene" "$integrator" "$threads" \
                    "$work/out" "${defines[@]}")
                read -r seconds rate <<< "$line"
                echo "$round,$name,$scene,$integrator,$seconds,$rate" | tee -a "$out"
            done
        done
    done
done
echo "load average after the benchmark: $(cat /proc/loadavg)" >&2
/usr/bin/python3 "$root/bench/tools/build_ab.py" "$out"
