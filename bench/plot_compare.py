#!/usr/bin/env python3
"""Summarises and plots bench/run_compare.sh: compare_rays.csv and compare_transient.csv (one
row per build, round and configuration) -> compare_summary.csv (medians over rounds per build,
after / before of the medians, and the median of the per-round after / before) and compare.png (every round's figures per build)."""
import csv
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


# (file, row filter, column, label) of every figure compared.
MEASURES = [
    ("rays", lambda r: r["scene"] == "cornell-box", "femto_median_mrays_per_s",
     "femto Mrays/s (Cornell box)"),
    ("rays", lambda r: r["scene"] == "cornell-box", "ratio", "femto / raw Embree ray rate"),
    ("transient", lambda r: r["variant"] == "steady", "median_samples_per_s",
     "steady samples/s"),
    ("transient", lambda r: r["variant"] == "transient", "samples_ratio_vs_steady",
     "transient / steady sample rate"),
]


def main():
    results = sys.argv[1] if len(sys.argv) > 1 else "bench/results"
    tables = {k: read_csv(os.path.join(results, f"compare_{k}.csv")) for k in ("rays", "transient")}
    rows, series = [], []
    for kind, keep, column, label in MEASURES:
        per_build, by_round = {}, {}
        for r in tables[kind]:
            if keep(r):
                per_build.setdefault(r["build"], []).append(float(r[column]))
                by_round.setdefault(r["round"], {})[r["build"]] = float(r[column])
        # after / before within each round (both ran back to back), robust to slow drift
        paired = [v["after"] / v["before"] for v in by_round.values()
                  if "after" in v and "before" in v and v["before"] > 0]
        before, after = per_build.get("before", []), per_build.get("after", [])
        if not before or not after:
            sys.exit(f"plot_compare.py: no rows for {label}")
        mb, ma = statistics.median(before), statistics.median(after)
        rows.append({"measure": label, "rounds": len(before), "before_median": f"{mb:.4g}",
                     "after_median": f"{ma:.4g}", "after_over_before": f"{ma / mb:.4f}",
                     "paired_median": f"{statistics.median(paired):.4f}",
                     "paired_min": f"{min(paired):.4f}", "paired_max": f"{max(paired):.4f}",
                     "before_min": f"{min(before):.4g}", "before_max": f"{max(before):.4g}",
                     "after_min": f"{min(after):.4g}", "after_max": f"{max(after):.4g}"})
        series.append((label, before, after))
    with open(os.path.join(results, "compare_summary.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    for r in rows:
        print(f"{r['measure']:<34} before {r['before_median']:>9}  after {r['after_median']:>9}"
              f"  after/before {r['after_over_before']}  paired {r['paired_median']}"
              f" [{r['paired_min']}, {r['paired_max']}]")

    fig, axes = plt.subplots(1, len(series), figsize=(4 * len(series), 3.4))
    for ax, (label, before, after) in zip(axes, series):
        ax.plot(range(len(before)), before, "o-", label="before")
        ax.plot(range(len(after)), after, "s-", label="after")
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("round")
        ax.set_ylim(bottom=0)
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(os.path.join(results, "compare.png"), dpi=110)


if __name__ == "__main__":
    main()
