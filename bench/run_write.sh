#!/usr/bin/env bash
# Builds femto with the benchmarks, runs femto_bench_write (cube writing speed per compression
# and thread count, peak memory of render + write up to 2^20 bins) and plots the results.
#   bench/run_write.sh [femto_bench_write options...]    e.g. --runs 7 --mode speed
# Results: bench/results/write_*.{csv,txt}, write.png, write_run.log. About 10 minutes on the
# 2-core machine once built (the 2^20-bin memory case alone writes a 3 GiB cube).
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build femto_bench_write

log="$results/write_run.log"
bench_log_header "$log"
"$build/bin/femto_bench_write" --out "$results" "$@" 2>&1 | tee -a "$log"
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"

/usr/bin/python3 "$root/bench/plot_write.py" "$results"

echo
echo "results in $results:"
echo "  write_speed.csv, write_speed_summary.csv     every round; medians and ratios"
echo "  write_memory.csv                             peak RSS per child (render, render + write)"
echo "  write.png, write_meta.txt, write_run.log"
