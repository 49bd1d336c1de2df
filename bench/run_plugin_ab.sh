#!/usr/bin/env bash
# Two builds of an integrator plugin side by side, with the path tracer as the yardstick:
#
#     bench/run_plugin_ab.sh OUT_CSV OLD_DIR NEW_DIR SCENE_XML INTEGRATOR ROUNDS THREADS [-D NAME=VALUE ...]
#
# Each round renders SCENE_XML with INTEGRATOR from OLD_DIR, then from NEW_DIR (each through
# `femto render --plugin-dir`: a folder holding the plugin's .so, and any other plugins of that
# build to compare with it), then with transient_path from femto's own plugins, each in a
# steady copy of the scene (common.sh's steady_scene_with, as run_ray_rate.sh renders).
# Rows `round,build,integrator,seconds,mrays` go to OUT_CSV; tools/plugin_ab.py summarises them
# (the new build's time over the old one's per round, each build's rays/s over the path
# tracer's). How to get OLD_DIR: build the plugin at the old revision (or keep a copy of
# build-bench/plugins/NAME.so before rebuilding). Uses the bench build's femto.
# OLD_DIR or NEW_DIR written lib:DIR compares two builds of libfemto instead: DIR holds a
# libfemto.so.* (a copy of build-bench/lib's), loaded through LD_LIBRARY_PATH with femto's own
# plugins.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
if [[ $# -lt 7 ]]; then
    sed -n '2,16p' "$0"
    exit 2
fi
out=$1 old=$2 new=$3 scene=$4 integrator=$5 rounds=$6 threads=$7
shift 7
for dir in "${old#lib:}" "${new#lib:}"; do
    [[ -d "$dir" ]] || { echo "run_plugin_ab.sh: $dir is not a folder" >&2; exit 2; }
done
[[ -f "$scene" ]] || { echo "run_plugin_ab.sh: $scene: no such file" >&2; exit 2; }
bench_build  # everything: the CLI and its plugins

work=$(mktemp -d)
xml=$(mktemp -p "$(dirname "$scene")" ".plugin-ab-XXXXXX.xml")
trap 'rm -rf "$work" "$xml"' EXIT
bench_log_header "$work/log" >&2
echo "round,build,integrator,seconds,mrays" > "$out"
for round in $(seq 1 "$rounds"); do
    for which in old new path; do
        name=$integrator
        prefix=()  # words before femto's path, and after the scene, that select the build
        suffix=()
        case $which in
            old | new)
                dir=${!which}
                if [[ $dir == lib:* ]]; then
                    # (libfemto finds plugins next to itself: name the build's.)
                    prefix=(env "LD_LIBRARY_PATH=${dir#lib:}")
                    suffix=(--plugin-dir "$build/plugins")
                else
                    suffix=(--plugin-dir "$dir")
                fi
                ;;
            path) name=transient_path ;;
        esac
        steady_scene_with "$name" "$scene" > "$xml"
        line=$("${prefix[@]}" "$build/bin/femto" render "$xml" "$@" --threads "$threads" \
            -o "$work/out" "${suffix[@]}" 2>&1 | render_seconds_and_rate)
        rm -rf "$work"/out*
        read -r seconds rate <<< "$line"
        echo "$round,$which,$name,$seconds,$rate" | tee -a "$out"
    done
done
echo "load average after the benchmark: $(cat /proc/loadavg)" >&2
/usr/bin/python3 "$root/bench/tools/plugin_ab.py" "$out"
