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
if [[ $# -lt 3 ]]; then
    sed -n '2,13p' "$0"
    exit 2
fi
out=$1 build_a=$2 build_b=$3 rounds=${4:-10} threads=${5:-2}
for dir in "$build_a" "$build_b"; do
    [[ -x "$dir/bin/femto" ]] || { echo "run_build_ab.sh: $dir/bin/femto: no such program" >&2; exit 2; }
done

work=$(mktemp -d)
temp_scenes=()
trap 'rm -rf "$work" "${temp_scenes[@]}"' EXIT
bench_log_header "$work/log" >&2
scenes=(
    "cornell-box|-D res=64 -D spp=256"
    "fog-object|-D res=32 -D spp=256"
    "caustic|-D res=64 -D spp=256"
)
echo "round,build,scene,integrator,seconds,mrays" > "$out"
for round in $(seq 1 "$rounds"); do
    order=("$build_a" "$build_b")
    (( round % 2 == 0 )) && order=("$build_b" "$build_a")
    for entry in "${scenes[@]}"; do
        scene=${entry%%|*}
        read -r -a defines <<< "${entry#*|}"
        for dir in "${order[@]}"; do
            for integrator in transient_path transient_bdpt; do
                # Next to the scene: it includes files by paths relative to its folder.
                xml=$(mktemp -p "$root/scenes/$scene" ".build-ab-$integrator-XXXXXX.xml")
                temp_scenes+=("$xml")
                steady_scene_with "$integrator" "$root/scenes/$scene/scene.xml" > "$xml"
                line=$("$dir/bin/femto" render "$xml" "${defines[@]}" --threads "$threads" \
                    -o "$work/out" 2>&1 | render_seconds_and_rate)
                read -r seconds rate <<< "$line"
                name=$([[ $dir == "$build_a" ]] && echo A || echo B)
                echo "$round,$name,$scene,$integrator,$seconds,$rate" | tee -a "$out"
            done
        done
    done
done
echo "load average after the benchmark: $(cat /proc/loadavg)" >&2
/usr/bin/python3 "$root/bench/tools/build_ab.py" "$out"
