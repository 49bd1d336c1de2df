#!/usr/bin/python3
"""Tables and a plot for the `bdpt` part of femto_bench_media (bench/media.cpp): time sampling
in transient_bdpt on scenes/fog-object, the setting of thesis Fig. 5.8-5.9.

    /usr/bin/python3 bench/plot_media_bdpt.py [RESULTS_DIR]      (default bench/results)

Reads media_bdpt_error.csv; writes
  media_bdpt_ratio.csv   for every medium, metric and budget: the equal-error sample and
                         wall-clock ratios of each BDPT strategy against BDPT's steady sampling,
                         and of BDPT against the path tracer's steady sampling (`steady`);
  media_bdpt_tables.md   the tables quoted in bench/README.md;
  media_bdpt_error.png   frame error against spp, every strategy, every medium.
Equal error: the baseline's spp with the same median error, log-log interpolated between its
medians (beyond them extrapolated along slope -1 and flagged with *), as plot_media.py does.
"""
import csv
import math
import os
import sys
from collections import defaultdict
from statistics import median

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ratios import equal_error_spp  # noqa: E402

RESULTS = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "results")
METRICS = ("frame_relmse", "pixel_relmse")
# (strategy, baseline): what each ratio compares.
PAIRS = (("bdpt_time", "bdpt_steady"), ("bdpt_equiangular", "bdpt_steady"),
         ("bdpt_time_all", "bdpt_steady"), ("bdpt_angular", "bdpt_steady"),
         ("bdpt_time_full", "bdpt_steady"), ("bdpt_steady", "steady"))
COLOURS = {"steady": "tab:blue", "bdpt_steady": "black", "bdpt_time": "tab:red",
           "bdpt_equiangular": "tab:green", "bdpt_time_all": "tab:purple",
           "bdpt_angular": "tab:orange", "bdpt_time_full": "tab:brown"}

with open(os.path.join(RESULTS, "media_bdpt_error.csv")) as f:
    rows = [r for r in csv.DictReader(f) if r["part"] == "bdpt"]
groups = defaultdict(list)
for r in rows:
    groups[(float(r["sigma_s"]), float(r["g"]), r["strategy"], int(r["spp"]))].append(r)
med = {k: {**{m: median(float(r[m]) for r in v) for m in METRICS},
           "wall": median(float(r["wall_s"]) for r in v)} for k, v in groups.items()}
media = sorted({(k[0], k[1]) for k in med})


def curve(s, g, strategy, metric):
    return sorted((k[3], v[metric], v["wall"]) for k, v in med.items()
                  if k[0] == s and k[1] == g and k[2] == strategy)


ratio_rows = []
for s, g in media:
    for metric in METRICS:
        for strategy, base in PAIRS:
            baseline = curve(s, g, base, metric)
            for n, e, w in curve(s, g, strategy, metric):
                n_eq, w_eq, how = equal_error_spp(baseline, e)
                ratio_rows.append({"strategy": strategy, "baseline": base, "sigma_s": s, "g": g,
                                   "metric": metric, "spp": n, "error": e, "wall_s": w,
                                   "baseline_spp_equal_error": n_eq, "sample_ratio": n_eq / n,
                                   "time_ratio": w_eq / w if w > 0 else float("nan"),
                                   "how": how})
with open(os.path.join(RESULTS, "media_bdpt_ratio.csv"), "w", newline="") as f:
    wr = csv.DictWriter(f, fieldnames=list(ratio_rows[0].keys()) if ratio_rows else ["none"])
    wr.writeheader()
    wr.writerows(ratio_rows)


def cell(strategy, base, s, g, metric, spp):
    rr = [r for r in ratio_rows if (r["strategy"], r["baseline"], r["sigma_s"], r["g"],
                                    r["metric"], r["spp"]) == (strategy, base, s, g, metric, spp)]
    if not rr or not math.isfinite(rr[0]["sample_ratio"]):
        return "n/a / n/a"
    r = rr[0]
    flag = "*" if r["how"] == "extrapolated" else ""
    return f"{r['sample_ratio']:.2f}{flag} / {r['time_ratio']:.2f}{flag}"


top = max((r["spp"] for r in ratio_rows), default=0)
lines = [f"Equal-error ratios at {top} spp, samples / wall-clock time (how many more samples and "
         f"how much more time the baseline needs for the same median error; * extrapolated "
         f"along slope -1). `bdpt_time`: exponential distances MIS-combined with mean free "
         f"paths; `bdpt_equiangular`: equiangular placed vertices; `bdpt_time_all`: "
         f"exponential distances (mis) and line_to_point placed vertices; `bdpt_angular`: "
         f"time-angular directions MIS-mixed with the phase function; `bdpt_time_full`: all "
         f"three (exponential, line_to_point, time-angular, mis); `steady`: the path "
         f"tracer's steady sampling.\n",
         "| sigma_s | g | metric | " + " | ".join(f"{a} vs {b}" for a, b in PAIRS) + " |",
         "|---|---|---|" + "---|" * len(PAIRS)]
for s, g in media:
    for metric in METRICS:
        lines.append(f"| {s} | {g} | {metric.split('_')[0]} | " +
                     " | ".join(cell(a, b, s, g, metric, top) for a, b in PAIRS) + " |")
with open(os.path.join(RESULTS, "media_bdpt_tables.md"), "w") as f:
    f.write("\n".join(lines) + "\n")
print("\n".join(lines))

if media:
    gs = sorted({g for _, g in media})
    ss = sorted({s for s, _ in media})
    fig, axes = plt.subplots(len(gs), len(ss), figsize=(4 * len(ss), 3.2 * len(gs)),
                             squeeze=False)
    for i, g in enumerate(gs):
        for j, s in enumerate(ss):
            ax = axes[i][j]
            for strategy, colour in COLOURS.items():
                pts = [p for p in curve(s, g, strategy, "frame_relmse") if p[1] > 0]
                if pts:
                    ax.loglog([p[0] for p in pts], [p[1] for p in pts], "-o", ms=3,
                              color=colour, label=strategy)
            ax.set_title(f"sigma_s {s}, g {g}", fontsize=9)
            ax.set_xlabel("spp")
            ax.set_ylabel("frame relMSE")
            ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, "media_bdpt_error.png"), dpi=110)
print(f"wrote media_bdpt_ratio.csv, media_bdpt_tables.md and media_bdpt_error.png in {RESULTS}")
