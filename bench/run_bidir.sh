#!/usr/bin/env bash
# Error against time of transient_path, transient_light and transient_bdpt on caustic,
# cornell-box and fog-object with the histogram and kernel filters (issue 11): equal-error time
# ratios with bootstrap intervals, and each integrator's ray rate against the path tracer's.
#   bench/run_bidir.sh [--quick]     about an hour on 2 cores once built (--quick: 5 min)
#   bench/run_bidir.sh --scene S --tfilter F --budgets A,B,.. [--ref-spp N] --prefix P
#                                    one scene and filter at other budgets, into P_*
# Results: bench/results/bidir_runs.csv, bidir_ratios.csv, bidir.png, bidir_run.log (or P_*).
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build  # the CLI and its plugins
prefix=bidir
args=("$@")
for ((i = 0; i + 1 < ${#args[@]}; i++)); do
    if [[ ${args[i]} == --prefix ]]; then prefix=${args[i + 1]}; fi
done
log="$results/${prefix}_run.log"
bench_log_header "$log"
/usr/bin/python3 "$root/bench/bidir.py" "$build/bin/femto" "$results" "$@" 2>&1 | tee -a "$log"
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"
