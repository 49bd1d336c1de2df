#!/usr/bin/env python3
"""Summarises and plots bench/run_compare.sh: compare_runs.csv (`femto bench` rows of both
builds, every round) -> compare_summary.csv (per scene and variant: median samples/s and rays/s
of each build, after / before of the medians, and the median of the per-round after / before)
and compare.png (every run's samples/s per build); with compare_raw_rays.csv, each run's ray rate
over Embree's raw rates (compare_raw_ratios.csv)."""
import csv
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    results = sys.argv[1] if len(sys.argv) > 1 else "bench/results"
    with open(os.path.join(results, "compare_runs.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    # (scene, variant) -> build -> round -> [samples/s], [rays/s]
    data = {}
    for r in rows:
        seconds = float(r["seconds"])
        if seconds <= 0:
            continue
        cell = data.setdefault((r["scene"], r["variant"]), {}).setdefault(r["build"], {})
        rates = cell.setdefault(r["round"], ([], []))
        rates[0].append(float(r["samples"]) / seconds)
        rates[1].append(float(r["rays"]) / seconds)
    out = [["scene", "variant", "measure", "before_median", "after_median", "after_over_before",
            "per_round_median", "per_round_min", "per_round_max"]]
    print(f"{'scene':<14} {'variant':<26} {'measure':<10} {'before':>10} {'after':>10} "
          f"{'after/before':>12} {'per round: median [min, max]':>30}")
    for (scene, variant), builds in sorted(data.items()):
        for k, measure in enumerate(("samples/s", "rays/s")):
            med = {b: statistics.median(x for rnd in builds.get(b, {}).values() for x in rnd[k])
                   for b in ("before", "after")}
            per_round = [statistics.median(builds["after"][rnd][k]) /
                         statistics.median(builds["before"][rnd][k])
                         for rnd in builds["after"] if rnd in builds.get("before", {})]
            ratio = med["after"] / med["before"]
            pr = (statistics.median(per_round), min(per_round), max(per_round))
            out.append([scene, variant, measure, f"{med['before']:.6g}", f"{med['after']:.6g}",
                        f"{ratio:.4f}"] + [f"{v:.4f}" for v in pr])
            print(f"{scene:<14} {variant:<26} {measure:<10} {med['before']:>10.4g} "
                  f"{med['after']:>10.4g} {ratio:>12.3f}   {pr[0]:.3f} [{pr[1]:.3f}, {pr[2]:.3f}]")
    with open(os.path.join(results, "compare_summary.csv"), "w", newline="") as f:
        csv.writer(f).writerows(out)
    raw_ratios(results, rows)
    fig, ax = plt.subplots(figsize=(8, 4))
    labels = []
    for i, ((scene, variant), builds) in enumerate(sorted(data.items())):
        labels.append(f"{scene}\n{variant}")
        for j, (b, colour) in enumerate((("before", "tab:blue"), ("after", "tab:red"))):
            values = [x for rnd in builds.get(b, {}).values() for x in rnd[0]]
            ax.scatter([i + (j - 0.5) * 0.2] * len(values), values, color=colour, s=12,
                       label=b if i == 0 else None)
    ax.set_xticks(range(len(labels)), labels, fontsize=8)
    ax.set_ylabel("camera samples per second")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(results, "compare.png"), dpi=120)


def raw_ratios(results, rows):
    """With compare_raw_rays.csv (experiments with <raw_rays>): each run's rays per second over
    Embree's raw rate of each kind measured just before it (same build, round, scene, budget
    and seed); the median and range per build, written to compare_raw_ratios.csv."""
    path = os.path.join(results, "compare_raw_rays.csv")
    if not os.path.exists(path):
        return
    raw = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            key = (r["build"], r["round"], r["scene"], r["budget"], r["seed"], r["kind"])
            raw[key] = float(r["rays"]) / float(r["seconds"])
    ratios = {}  # (scene, variant, kind) -> build -> [ratio]
    for r in rows:
        seconds = float(r["seconds"])
        if seconds <= 0:
            continue
        for kind in ("incoherent", "sorted", "shadow"):
            base = raw.get((r["build"], r["round"], r["scene"], r["budget"], r["seed"], kind))
            if base:
                ratios.setdefault((r["scene"], r["variant"], kind), {}).setdefault(
                    r["build"], []).append(float(r["rays"]) / seconds / base)
    out = [["scene", "variant", "raw_kind", "build", "median", "min", "max", "runs"]]
    print(f"\n{'scene':<16} {'variant':<20} {'over raw':<10} {'before: median [min, max]':>28} "
          f"{'after: median [min, max]':>28}")
    for (scene, variant, kind), builds in sorted(ratios.items()):
        cells = []
        for b in ("before", "after"):
            v = builds.get(b, [])
            if not v:
                cells.append(f"{'-':>28}")
                continue
            m = statistics.median(v)
            out.append([scene, variant, kind, b, f"{m:.4f}", f"{min(v):.4f}", f"{max(v):.4f}",
                        len(v)])
            cells.append(f"{m:>12.3f} [{min(v):.3f}, {max(v):.3f}]")
        print(f"{scene:<16} {variant:<20} {kind:<10} {cells[0]} {cells[1]}")
    with open(os.path.join(results, "compare_raw_ratios.csv"), "w", newline="") as f:
        csv.writer(f).writerows(out)


if __name__ == "__main__":
    main()
