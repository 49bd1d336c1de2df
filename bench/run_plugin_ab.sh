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
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
if [[ $# -lt 7 ]]; then
    sed -n '2,13p' "$0"
    exit 2
fi
out=$1 old=$2 new=$3 scene=$4 integrator=$5 rounds=$6 threads=$7
shift 7
for dir in "$old" "$new"; do
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
        args=()
        case $which in
            old) args=(--plugin-dir "$old") ;;
            new) args=(--plugin-dir "$new") ;;
            path) name=transient_path ;;
        esac
        steady_scene_with "$name" "$scene" > "$xml"
        line=$("$build/bin/femto" render "$xml" "$@" --threads "$threads" -o "$work/out" \
            "${args[@]}" 2>&1 | render_seconds_and_rate)
        rm -rf "$work"/out*
        read -r seconds rate <<< "$line"
        echo "$round,$which,$name,$seconds,$rate" | tee -a "$out"
    done
done
echo "load average after the benchmark: $(cat /proc/loadavg)" >&2
/usr/bin/python3 "$root/bench/tools/plugin_ab.py" "$out"
