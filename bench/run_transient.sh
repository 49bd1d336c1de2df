#!/usr/bin/env bash
# Builds femto with the benchmarks, runs femto_bench_transient (throughput, memory, error
# against time) and plots the results.
#   bench/run_transient.sh [femto_bench_transient options...]    e.g. --runs 7
# Results: bench/results/transient_*.{csv,txt,png}, transient_run.log. About 5-8 minutes on
# the 2-core machine once built (the first run also renders the error reference, ~1-2 min).
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build femto_bench_transient

log="$results/transient_run.log"
bench_log_header "$log"
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
