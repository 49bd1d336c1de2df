#!/usr/bin/env bash
# Before/after throughput of two revisions, measured side by side: builds REV (a detached
# worktree) and the working tree, then runs both builds' `femto bench EXPERIMENT` (the working
# tree's file and scenes, for both) in ROUNDS rounds, swapping which build goes first every
# round so that drift in the machine's load hits both. When valgrind is installed it also counts
# the instructions of femto::render() for both builds (callgrind; deterministic, unlike seconds
# on a shared machine). REV needs `femto bench` and every element EXPERIMENT uses.
#   bench/run_compare.sh REV [ROUNDS] [EXPERIMENT]
#       e.g. bench/run_compare.sh 4a3e41b 5      (EXPERIMENT: bench/experiments/compare.xml)
#   FEMTO_BENCH_ARGS="--threads 1" bench/run_compare.sh ...  passes options to `femto bench`
# Results: bench/results/compare_runs.csv (every run of both builds), compare_summary.csv,
# compare.png, compare_instructions.csv, compare_run.log.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
rev=${1:?usage: run_compare.sh REV [ROUNDS] [EXPERIMENT]}
rounds=${2:-5}
experiment=$(realpath "${3:-$root/bench/experiments/compare.xml}")
base="$root/build-bench-compare"
before_src="$base/src-$rev"
before_build="$base/build-$rev"

bench_build  # the CLI and every plugin it loads
if [[ ! -d "$before_src" ]]; then
    mkdir -p "$base"
    git -C "$root" worktree add --detach "$before_src" "$rev" >/dev/null
fi
if [[ ! -f "$before_build/build.ninja" ]]; then
    cmake -S "$before_src" -B "$before_build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
        -DFEMTO_TESTS=OFF >/dev/null
fi
ninja -C "$before_build"

log="$results/compare_run.log"
bench_log_header "$log"
echo "before: $rev, after: working tree; $rounds rounds of $experiment" | tee -a "$log"
runs_csv="$results/compare_runs.csv"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
raw_csv="$results/compare_raw_rays.csv"
rm -f "$runs_csv" "$raw_csv"

# One round of one build: its study in a fresh folder, its rows prefixed with build and round.
run_one() {
    local label=$1 dir=$2 round=$3
    # shellcheck disable=SC2086  # FEMTO_BENCH_ARGS: extra options, e.g. "--threads 1"
    "$dir/bin/femto" bench "$experiment" -o "$tmp/$label-$round" -q ${FEMTO_BENCH_ARGS:-} \
        >>"$log" 2>&1
    [[ -f "$runs_csv" ]] || sed -n '1s/^/build,round,/p' "$tmp/$label-$round/results.csv" >"$runs_csv"
    sed -n "2,\$s/^/$label,$round,/p" "$tmp/$label-$round/results.csv" >>"$runs_csv"
    # Embree's raw rates measured beside the runs (experiments with <raw_rays>).
    if [[ -f "$tmp/$label-$round/raw_rays.csv" ]]; then
        [[ -f "$raw_csv" ]] || sed -n '1s/^/build,round,/p' "$tmp/$label-$round/raw_rays.csv" >"$raw_csv"
        sed -n "2,\$s/^/$label,$round,/p" "$tmp/$label-$round/raw_rays.csv" >>"$raw_csv"
    fi
}

for ((r = 0; r < rounds; r++)); do
    if ((r % 2 == 0)); then
        run_one before "$before_build" "$r"
        run_one after "$build" "$r"
    else
        run_one after "$build" "$r"
        run_one before "$before_build" "$r"
    fi
    echo "round $r done (load $(cut -d' ' -f1-3 /proc/loadavg))" | tee -a "$log"
done
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"
/usr/bin/python3 "$root/bench/plot_compare.py" "$results" | tee -a "$log"

# Instructions executed by femto::render() (1 thread, 32x32 px, 16 spp), both builds.
if command -v valgrind >/dev/null; then
    preload=$(valgrind_preload)
    ins="$results/compare_instructions.csv"
    echo "scene,before_render_instructions,after_render_instructions,after_over_before" >"$ins"
    for scene in cornell-box fog-object; do
        counts=()
        for dir in "$before_build" "$build"; do
            rm -f "$tmp/cg.out"
            # valgrind cannot decode every instruction of every library femto loads (libhwy's
            # rdtscp, through OpenImageIO, on some systems; the preloaded shim avoids it): no
            # count then, not a failed script.
            LD_PRELOAD="$preload" valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.out" "$dir/bin/femto" render \
                "$root/scenes/$scene/scene.xml" -D res=32 -D spp=16 --threads 1 --quiet \
                -o "$tmp/cg" >/dev/null 2>&1 || true
            counts+=("$(callgrind_annotate --inclusive=yes "$tmp/cg.out" 2>/dev/null |
                grep -F 'femto::render(femto::Scene&, femto::RenderOptions const&) [' |
                awk '{gsub(",", "", $1); print $1}' || true)")
        done
        if [[ -z "${counts[0]}" || -z "${counts[1]}" ]]; then
            echo "$scene: valgrind could not run femto here; no instruction count" | tee -a "$log"
            continue
        fi
        awk -v s="$scene" -v a="${counts[0]}" -v b="${counts[1]}" \
            'BEGIN { printf "%s,%s,%s,%.4f\n", s, a, b, b / a }' >>"$ins"
    done
    column -t -s, "$ins" | tee -a "$log"
fi
