#!/usr/bin/env bash
# Builds femto with the benchmarks, runs femto_bench_transient (throughput, memory, error
# against time) and plots the results.
#   bench/run_transient.sh [femto_bench_transient options...]    e.g. --runs 7
# Results: bench/results/transient_*.{csv,txt,png}, transient_run.log. About 5-8 minutes on
# the 2-core machine once built (the first run also renders the error reference, ~1-2 min).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${FEMTO_BENCH_BUILD_DIR:-$root/build-bench}"
results="$root/bench/results"
mkdir -p "$results"

if [[ ! -f "$build/build.ninja" ]]; then
    cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFEMTO_BENCH=ON -DFEMTO_TESTS=OFF
fi
ninja -C "$build" femto_bench_transient

log="$results/transient_run.log"
{
    echo "source: git $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)" \
        "($(git -C "$root" status --porcelain 2>/dev/null | wc -l) uncommitted changes)"
    echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
    echo "date: $(date -u '+%Y-%m-%d %H:%M:%S UTC')"
    echo "load average before the benchmark: $(cat /proc/loadavg)"
} | tee "$log"
"$build/bin/femto_bench_transient" --out "$results" "$@" 2>&1 | tee -a "$log"
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"

# Debian's Python has matplotlib (a pyenv python3 on PATH may not).
/usr/bin/python3 "$root/bench/plot_transient.py" "$results"

echo
echo "results in $results:"
echo "  transient_throughput.csv    every throughput run; transient_summary.csv: medians, ratios"
echo "  transient_memory.csv        peak RSS per child run; transient_memory_summary.csv"
echo "  transient_error.csv         every error-vs-time render; transient_error_summary.csv"
echo "  transient_throughput.png, transient_error.png   the plots"
echo "  transient_meta.txt, transient_run.log"
