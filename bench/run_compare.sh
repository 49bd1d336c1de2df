#!/usr/bin/env bash
# Before/after throughput of two revisions, measured side by side in one run: builds REV (a
# detached worktree) and the working tree with the benchmarks, then alternates their
# femto_bench_rays (Cornell box, ray rate and its ratio to Embree's raw rate) and
# femto_bench_transient (throughput mode: transient/steady sample-rate ratio) ROUNDS times,
# swapping which goes first every round so that drift in the machine's load hits both. When
# valgrind is installed it also counts the instructions of femto::render() for both builds
# (callgrind; deterministic, unlike seconds on a shared machine).
#   bench/run_compare.sh REV [ROUNDS]        e.g. bench/run_compare.sh 4a3e41b 5
# Results: bench/results/compare_{rays,transient,summary,instructions}.csv, compare.png,
# compare_run.log.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
rev=${1:?usage: run_compare.sh REV [ROUNDS]}
rounds=${2:-5}
base="$root/build-bench-compare"
before_src="$base/src-$rev"
before_build="$base/build-$rev"

bench_build femto_bench_rays femto_bench_transient femto_cli
if [[ ! -d "$before_src" ]]; then
    mkdir -p "$base"
    git -C "$root" worktree add --detach "$before_src" "$rev" >/dev/null
fi
if [[ ! -f "$before_build/build.ninja" ]]; then
    cmake -S "$before_src" -B "$before_build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
        -DFEMTO_BENCH=ON -DFEMTO_TESTS=OFF >/dev/null
fi
ninja -C "$before_build" femto_bench_rays femto_bench_transient femto_cli

log="$results/compare_run.log"
bench_log_header "$log"
echo "before: $rev, after: working tree; $rounds rounds" | tee -a "$log"
rays_csv="$results/compare_rays.csv"
transient_csv="$results/compare_transient.csv"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
rm -f "$rays_csv" "$transient_csv"

# One round of one build: its rays and transient summaries, prefixed with build and round.
run_one() {
    local label=$1 dir=$2 src=$3 round=$4
    "$dir/bin/femto_bench_rays" --source-dir "$src" --out "$tmp/$label" --scenes cornell-box \
        --threads 1 --runs 3 >>"$log" 2>&1
    "$dir/bin/femto_bench_transient" --mode throughput --out "$tmp/$label" --threads 1 \
        --runs 3 --res 64 --spp 16 >>"$log" 2>&1
    for kind in rays transient; do
        local csv="$results/compare_$kind.csv"
        [[ -f "$csv" ]] || sed -n '1s/^/build,round,/p' "$tmp/$label/${kind}_summary.csv" >"$csv"
        sed -n "2,\$s/^/$label,$round,/p" "$tmp/$label/${kind}_summary.csv" >>"$csv"
    done
}

for ((r = 0; r < rounds; r++)); do
    if ((r % 2 == 0)); then
        run_one before "$before_build" "$before_src" "$r"
        run_one after "$build" "$root" "$r"
    else
        run_one after "$build" "$root" "$r"
        run_one before "$before_build" "$before_src" "$r"
    fi
    echo "round $r done (load $(cut -d' ' -f1-3 /proc/loadavg))" | tee -a "$log"
done
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"
/usr/bin/python3 "$root/bench/plot_compare.py" "$results" | tee -a "$log"

# Instructions executed by femto::render() (1 thread, 32x32 px, 16 spp), both builds.
if command -v valgrind >/dev/null; then
    ins="$results/compare_instructions.csv"
    echo "scene,before_render_instructions,after_render_instructions,after_over_before" >"$ins"
    for scene in cornell-box fog-object; do
        counts=()
        for pair in "$before_build:$before_src" "$build:$root"; do
            dir=${pair%%:*} src=${pair#*:}
            valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.out" "$dir/bin/femto" render \
                "$src/scenes/$scene/scene.xml" -D res=32 -D spp=16 --threads 1 --quiet \
                -o "$tmp/cg" >/dev/null 2>&1
            counts+=("$(callgrind_annotate --inclusive=yes "$tmp/cg.out" 2>/dev/null |
                grep -F 'femto::render(femto::Scene&, femto::RenderOptions const&) [' |
                awk '{gsub(",", "", $1); print $1}')")
        done
        awk -v s="$scene" -v a="${counts[0]}" -v b="${counts[1]}" \
            'BEGIN { printf "%s,%s,%s,%.4f\n", s, a, b, b / a }' >>"$ins"
    done
    column -t -s, "$ins" | tee -a "$log"
fi
