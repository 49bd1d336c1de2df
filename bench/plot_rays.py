#!/usr/bin/python3
"""Plots femto_bench_rays results: bench/results/rays.csv (+ rays_summary.csv, rays_meta.txt)
-> bench/results/rays.png, and the summary as a Markdown table -> bench/results/rays_table.md.

Per scene: median ray rates per thread count (Embree raw rtcIntersect1 on random incoherent
rays, the same rays ordered by origin, rtcOccluded1 shadow rays, femto `path`), each run as a
dot, the ratio femto / raw (random incoherent) annotated.
Right: the per-run ratio femto / raw (measured back to back; by wall clock and per second of
process CPU time), with the 0.7 goal.

Run with Debian's Python (it has matplotlib): /usr/bin/python3 bench/plot_rays.py [results_dir]
"""
import csv
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

GOAL = 0.7


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def read_meta(path):
    meta = {}
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                key, sep, value = line.partition(":")
                if sep:
                    meta[key.strip()] = value.strip()
    return meta


def markdown_table(summary, meta):
    """The summary as a Markdown table (what bench/README.md quotes)."""
    lines = [
        f"Machine: {meta.get('nproc', '?')} cores, {meta.get('cpu', '?')}; {meta.get('date', '?')}; "
        f"load average at start {meta.get('load_start', '?')}, at end {meta.get('load_end', '?')}. "
        f"Medians of {meta.get('runs', '?')} runs; Mray/s = million rays per second (wall clock).",
        "",
        "| scene | triangles | threads | raw Mray/s | femto Mray/s | **femto / raw** | paired | "
        "raw sorted Mray/s | femto / sorted | raw shadow Mray/s | femto / raw per CPU-s | "
        "cores used raw / femto | load before -> after |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for s in summary:
        lines.append(
            f"| {s['scene']} | {int(s['triangles']):,} | {s['threads']} | "
            f"{float(s['raw_median_mrays_per_s']):.2f} | {float(s['femto_median_mrays_per_s']):.2f} | "
            f"**{float(s['ratio']):.2f}** | {float(s['paired_ratio']):.2f} | "
            f"{float(s['raw_sorted_median_mrays_per_s']):.2f} | {float(s['sorted_ratio']):.2f} | "
            f"{float(s['raw_shadow_median_mrays_per_s']):.2f} | {float(s['cpu_ratio']):.2f} | "
            f"{float(s['raw_cores_used']):.2f} / {float(s['femto_cores_used']):.2f} | "
            f"{s['load_before'].split()[0]} -> {s['load_after'].split()[0]} |")
    return "\n".join(lines) + "\n"


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    results = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "results")
    runs = read_csv(os.path.join(results, "rays.csv"))
    summary = read_csv(os.path.join(results, "rays_summary.csv"))
    meta = read_meta(os.path.join(results, "rays_meta.txt"))
    if not summary:
        sys.exit("plot_rays.py: rays_summary.csv is empty")

    groups = [(s["scene"], int(s["threads"])) for s in summary]
    by_group = {g: [r for r in runs if (r["scene"], int(r["threads"])) == g] for g in groups}
    series = [
        ("raw_mrays_per_s", "Embree raw: rtcIntersect1, random incoherent rays", "#4c72b0", None),
        ("raw_sorted_mrays_per_s", "Embree raw: the same rays ordered by origin", "#8fa9d6", ".."),
        ("raw_shadow_mrays_per_s", "Embree raw: rtcOccluded1, shadow rays to the lights",
         "#c6d4ea", "//"),
        ("femto_mrays_per_s", "femto path: every ray (camera, bounce, shadow)", "#dd8452", None),
    ]

    scenes = list(dict.fromkeys(scene for scene, _ in groups))
    fig, axes = plt.subplots(1, len(scenes) + 1, figsize=(5.0 * len(scenes) + 4.5, 5.4),
                             gridspec_kw={"width_ratios": [1.6] * len(scenes) + [1]})
    width = 0.2
    for ax, scene in zip(axes, scenes):
        idx = [i for i, g in enumerate(groups) if g[0] == scene]
        for k, (col, label, color, hatch) in enumerate(series):
            offset = (k - 1.5) * width
            meds = [statistics.median(float(r[col]) for r in by_group[groups[i]]) for i in idx]
            ax.bar([x + offset for x in range(len(idx))], meds, width, label=label, color=color,
                   hatch=hatch, edgecolor="black", linewidth=0.5)
            for x, i in enumerate(idx):
                vals = [float(r[col]) for r in by_group[groups[i]]]
                ax.plot([x + offset] * len(vals), vals, "k.", markersize=3, alpha=0.6)
        top_all = 0.0
        for x, i in enumerate(idx):
            top = max(float(r[c]) for r in by_group[groups[i]] for c, *_ in series)
            top_all = max(top_all, top)
            ratio = float(summary[i]["ratio"])
            ax.annotate(f"femto/raw\n{ratio:.2f}", (x, top), xytext=(0, 6),
                        textcoords="offset points", ha="center", va="bottom", fontsize=9,
                        color="darkgreen" if ratio >= GOAL else "darkred", fontweight="bold")
        ax.set_xticks(list(range(len(idx))))
        ax.set_xticklabels([f"{groups[i][1]} thread{'s' if groups[i][1] > 1 else ''}" for i in idx])
        ax.set_ylim(0, top_all * 1.45)
        ax.set_ylabel("Mrays/s (bars = medians, dots = runs)")
        ax.grid(axis="y", alpha=0.3)
        ax.set_title(f"{scene} ({int(summary[idx[0]]['triangles']):,} triangles)", fontsize=10)
        ax.legend(fontsize=7, loc="upper left")

    axr = axes[-1]
    xs = range(len(groups))
    for x, g in zip(xs, groups):
        ratios = [float(r["femto_mrays_per_s"]) / float(r["raw_mrays_per_s"]) for r in by_group[g]]
        axr.plot([x - 0.08] * len(ratios), ratios, "o", color="#dd8452", alpha=0.6, markersize=4,
                 label="wall clock" if x == 0 else None)
        axr.hlines(statistics.median(ratios), x - 0.3, x + 0.3, color="black")
        cpu = [(int(r["femto_rays"]) / float(r["femto_cpu_seconds"]))
               / (int(r["raw_rays"]) / float(r["raw_cpu_seconds"]))
               for r in by_group[g] if float(r["femto_cpu_seconds"]) > 0
               and float(r["raw_cpu_seconds"]) > 0]
        axr.plot([x + 0.08] * len(cpu), cpu, "x", color="#55a868", markersize=5,
                 label="per CPU second" if x == 0 else None)
    axr.axhline(GOAL, color="darkred", linestyle="--", linewidth=1, label=f"goal {GOAL}")
    axr.set_xticks(list(xs))
    axr.set_xticklabels([f"{scene.split('-')[0]}\n{t}T" for scene, t in groups], fontsize=9)
    axr.set_ylabel("femto / raw, per run (line = median)")
    axr.set_ylim(0, max(1.1, axr.get_ylim()[1]))
    axr.legend(fontsize=8)
    axr.grid(axis="y", alpha=0.3)
    axr.set_title("Ratio per back-to-back run")

    fig.suptitle(
        f"femto_bench_rays: {meta.get('nproc', '?')} cores, {meta.get('cpu', '?')}, "
        f"{meta.get('date', '?')}; load avg start {meta.get('load_start', '?')}, "
        f"end {meta.get('load_end', '?')}; {meta.get('runs', '?')} runs",
        fontsize=9)
    fig.tight_layout()
    out = os.path.join(results, "rays.png")
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")
    table = os.path.join(results, "rays_table.md")
    with open(table, "w") as f:
        f.write(markdown_table(summary, meta))
    print(f"wrote {table}")


if __name__ == "__main__":
    main()
