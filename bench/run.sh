#!/usr/bin/env bash
# Builds femto with the benchmarks (build-bench/), runs femto_bench_rays and plots the results.
#   bench/run.sh [femto_bench_rays options...]      e.g. bench/run.sh --runs 9
# Results: bench/results/{rays.csv,rays_summary.csv,rays_meta.txt,rays.png,rays_table.md,run.log}.
# Takes ~3-6 minutes on the 2-core machine once built (the first build adds a few minutes).
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
echo "load average before build: $(cat /proc/loadavg)"
bench_build

{
    echo "source: git $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)" \
        "($(git -C "$root" status --porcelain -- . ':!bench' 2>/dev/null | wc -l) uncommitted" \
        "changes outside bench/)"
    echo "load average before the benchmark: $(cat /proc/loadavg)"
} | tee "$results/run.log"
"$build/bin/femto_bench_rays" --out "$results" "$@" 2>&1 | tee -a "$results/run.log"
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$results/run.log"

# Debian's Python has matplotlib (a pyenv python3 on PATH may not).
/usr/bin/python3 "$root/bench/plot_rays.py" "$results"

echo
echo "results in $results:"
echo "  rays.csv          every run (raw and femto rates, loads)"
echo "  rays_summary.csv  medians, femto/raw ratios, load before/after per configuration"
echo "  rays_meta.txt     machine, date, build, settings"
echo "  rays.png          the plot"
echo "  rays_table.md     the summary as a Markdown table (quoted in bench/README.md)"
echo "  run.log           this run's output"
