#!/usr/bin/env bash
# Builds femto with the benchmarks, runs femto_bench_kernel (error against time of the
# `kernel` temporal filter next to the histogram on cornell-box, tof-plane and spheres) and
# plots the results.
#   bench/run_kernel.sh [femto_bench_kernel options...]     e.g. --seeds 5
# Results: bench/results/kernel_*.{csv,txt,md,png}, kernel_run.log. About 15-20 minutes on the
# 2-core machine once built, references included (cached afterwards as ref_*.npy, ~4 min).
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build femto_bench_kernel

log="$results/kernel_run.log"
bench_log_header "$log"
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
