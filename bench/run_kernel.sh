#!/usr/bin/env bash
# Builds femto with the benchmarks, runs femto_bench_kernel (error against time of the
# `kernel` temporal filter next to the histogram on cornell-box, tof-plane and spheres) and
# plots the results.
#   bench/run_kernel.sh [femto_bench_kernel options...]     e.g. --seeds 5
# Results: bench/results/kernel_*.{csv,txt,md,png}, kernel_run.log. About 15-20 minutes on the
# 2-core machine once built, references included (cached afterwards as ref_*.npy, ~4 min).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${FEMTO_BENCH_BUILD_DIR:-$root/build-bench}"
results="$root/bench/results"
mkdir -p "$results"

if [[ ! -f "$build/build.ninja" ]]; then
    cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DFEMTO_BENCH=ON -DFEMTO_TESTS=OFF
fi
# A new plugin folder (plugins/<kind>/<type>/) is found at configure time: reconfigure when
# the kernel filter is not part of the build yet.
if ! grep -q "femto_plugin_kernel" "$build/build.ninja"; then
    cmake "$build" >/dev/null
fi
ninja -C "$build" femto_bench_kernel

log="$results/kernel_run.log"
{
    echo "source: git $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)" \
        "($(git -C "$root" status --porcelain 2>/dev/null | wc -l) uncommitted changes)"
    echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
    echo "date: $(date -u '+%Y-%m-%d %H:%M:%S UTC')"
    echo "load average before the benchmark: $(cat /proc/loadavg)"
} | tee "$log"
"$build/bin/femto_bench_kernel" --out "$results" "$@" 2>&1 | tee -a "$log"
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"

# Debian's Python has matplotlib (a pyenv python3 on PATH may not).
/usr/bin/python3 "$root/bench/plot_kernel.py" "$results" | tee -a "$log"

echo
echo "results in $results:"
echo "  kernel_error.csv          every render: time and the error measures"
echo "  kernel_error_summary.csv  medians per scene, variant and spp"
echo "  kernel_speedup.csv        equal-error speed-up of each kernel point over the histogram"
echo "  kernel_slopes.csv         fitted log-log slopes of error against time"
echo "  kernel_profiles.csv       selected pixels' time profiles (Fig. 5.5)"
echo "  kernel_scenes.csv, kernel_meta.txt, kernel_run.log, kernel_tables.md"
echo "  kernel_error.png, kernel_sweep.png, kernel_profile.png"
