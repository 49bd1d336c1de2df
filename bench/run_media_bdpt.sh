#!/usr/bin/env bash
# Builds femto with the benchmarks, runs the `bdpt` part of femto_bench_media (time sampling in
# transient_bdpt on scenes/fog-object at sigma_s 0.2 / 0.9 / 1.5, g 0 / +-0.8: the setting of
# thesis Fig. 5.8-5.9) and tabulates the equal-error ratios.
#   bench/run_media_bdpt.sh [femto_bench_media options...]     e.g. --seeds 3
# Results: bench/results/media_bdpt_*.{csv,txt,md,png}, media_bdpt_run.log. The references are
# those of bench/run_media.sh (cached as ref_media_*.npy; rendered on the first run).
set -euo pipefail

source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bench_build femto_bench_media

log="$results/media_bdpt_run.log"
bench_log_header "$log"
"$build/bin/femto_bench_media" --out "$results" --prefix media_bdpt --parts bdpt "$@" 2>&1 |
    tee -a "$log"
echo "load average after the benchmark: $(cat /proc/loadavg)" | tee -a "$log"

/usr/bin/python3 "$root/bench/plot_media_bdpt.py" "$results" | tee -a "$log"

echo
echo "results in $results:"
echo "  media_bdpt_error.csv   every render: time and the error measures"
echo "  media_bdpt_ratio.csv   equal-error sample and time ratios"
echo "  media_bdpt_tables.md   the table quoted in bench/README.md"
echo "  media_bdpt_error.png, media_bdpt_frames.csv, media_bdpt_meta.txt, media_bdpt_run.log"
