#!/usr/bin/env bash
# Builds femto with the benchmarks and runs femto_bench_ceiling: Embree's raw incoherent rate,
# a minimal path tracer over the same BVH with femto's pieces swapped in one at a time, and
# femto's `path`, interleaved on the Cornell box (issue 17's yardstick), then plots them.
#   bench/run_ceiling.sh [--rounds 7] [--threads 1] [--spp 8] [--res 256]
# Results: bench/results/ceiling/ceiling_<threads>t.{csv,png} and _run.log. About 90 s for
# 7 rounds at 1 thread on the 2-core machine once built.
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build femto_bench_ceiling

threads=1
args=("$@")
for ((i = 0; i < ${#args[@]}; ++i)); do
  [ "${args[i]}" = "--threads" ] && threads="${args[i + 1]:-1}"
done
out="$results/ceiling"
mkdir -p "$out"
log="$out/ceiling_${threads}t_run.log"
bench_log_header "$log"
"$build/bin/femto_bench_ceiling" --out "$out/ceiling_${threads}t.csv" "$@" 2>&1 | tee -a "$log"
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"
/usr/bin/python3 "$root/bench/plot_ceiling.py" "$out/ceiling_${threads}t.csv"
