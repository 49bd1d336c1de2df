#!/usr/bin/python3
"""Plots and tables for femto_bench_media (bench/media.cpp): the time-sampling strategies of
thesis ch. 5.6 against steady-state sampling on scenes/fog-object.

    /usr/bin/python3 bench/plot_media.py [RESULTS_DIR]      (default bench/results)

Reads media_error.csv and media_frames.csv; writes
  media_ratio.csv     for every medium, metric and time-strategy budget: the steady spp with the
                      same median error (log-log interpolation of the steady medians; beyond
                      them, extrapolation along slope -1, the Monte Carlo rate, flagged), the
                      sample ratio steady / time, and the same as a wall-clock ratio;
  media_combos.csv    every strategy combination at every budget: median error, median time,
                      and the efficiency 1 / (error x time) relative to steady sampling;
  media_tables.md     the tables quoted in bench/README.md;
  media_error.png     frame error against spp, steady vs time, every medium (Fig. 5.8/5.9);
  media_profiles.png  pixel (a)'s time profile: reference, steady and time at equal spp;
  media_error_time.png  error per frame over time at the largest budget;
  media_single.png    Fig. 5.10: single scattering, error per frame and samples per frame;
  media_combos.png    every combination: frame error against wall-clock time.
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


def read(name):
    with open(os.path.join(RESULTS, name)) as f:
        return list(csv.DictReader(f))


errors = read("media_error.csv")
frames = read("media_frames.csv")
METRICS = ["frame_relmse", "pixel_relmse", "cube_relmse"]


def key(r):
    return (r["part"], float(r["sigma_s"]), float(r["g"]), r["strategy"], int(r["spp"]))


# Medians over seeds of every error measure and of the wall time.
groups = defaultdict(list)
for r in errors:
    groups[key(r)].append(r)
med = {}
for k, rows in groups.items():
    med[k] = {m: median(float(r[m]) for r in rows) for m in METRICS}
    med[k]["wall"] = median(float(r["wall_s"]) for r in rows)
    med[k]["n"] = len(rows)


def curve(part, s, g, strategy, metric):
    pts = sorted((k[4], v[metric], v["wall"]) for k, v in med.items()
                 if k[0] == part and k[1] == s and k[2] == g and k[3] == strategy)
    return pts


media = sorted({(k[1], k[2]) for k in med if k[0] == "media"})
bundles = sorted({k[3] for k in med if k[0] == "media"} - {"steady"})
ratio_rows = []
for s, g in media:
    for metric in METRICS[:2]:
        steady = curve("media", s, g, "steady", metric)
        for b in bundles:
            for n, e, w in curve("media", s, g, b, metric):
                n_eq, w_eq, how = equal_error_spp(steady, e)
                ratio_rows.append({"strategy": b, "sigma_s": s, "g": g, "metric": metric,
                                   "time_spp": n, "time_error": e, "time_wall_s": w,
                                   "steady_spp_equal_error": n_eq, "sample_ratio": n_eq / n,
                                   "time_ratio": w_eq / w if w > 0 else "", "how": how})
with open(os.path.join(RESULTS, "media_ratio.csv"), "w", newline="") as f:
    wr = csv.DictWriter(f, fieldnames=list(ratio_rows[0].keys()) if ratio_rows else ["none"])
    wr.writeheader()
    wr.writerows(ratio_rows)

# Every combination: efficiency relative to steady at each budget.
combo_rows = []
combos = sorted({k[3] for k in med if k[0] == "combos"})
for c in combos:
    for n, e, w in curve("combos", 0.9, 0.0, c, "frame_relmse"):
        base = [x for x in curve("combos", 0.9, 0.0, "mean_free_path/deterministic/phase",
                                 "frame_relmse") if x[0] == n]
        eff = 1.0 / (e * w) if e > 0 and w > 0 else float("nan")
        rel = eff * base[0][1] * base[0][2] if base and base[0][1] > 0 else float("nan")
        combo_rows.append({"strategy": c, "spp": n, "frame_relmse": e, "wall_s": w,
                           "efficiency_vs_steady": rel})
with open(os.path.join(RESULTS, "media_combos.csv"), "w", newline="") as f:
    wr = csv.DictWriter(f, fieldnames=["strategy", "spp", "frame_relmse", "wall_s",
                                       "efficiency_vs_steady"])
    wr.writeheader()
    wr.writerows(combo_rows)

# Tables.
lines = []
top = max((r["time_spp"] for r in ratio_rows), default=0)
lines.append(f"Equal-error ratios over steady sampling at {top} spp: how many more samples (and "
             f"how much more wall-clock time) steady sampling needs for the same median error. "
             f"`time`: exponential + line_to_point + time angular, mis; `time_mfp`: the same "
             f"with mean-free-path distances.\n")
lines.append("| strategy | sigma_s | g | frame error: samples | frame error: time | pixel (a): "
             "samples | pixel (a): time |")
lines.append("|---|---|---|---|---|---|---|")


def fmt_ratio(r):
    if not r or not math.isfinite(r["sample_ratio"]):
        return "n/a", "n/a"
    flag = "*" if r["how"] == "extrapolated" else ""
    t = r["time_ratio"]
    return (f"{r['sample_ratio']:.2f}{flag}", f"{t:.2f}{flag}" if t != "" else "n/a")


for b in bundles:
    for s, g in media:
        cells = []
        for metric in METRICS[:2]:
            rr = [r for r in ratio_rows if r["strategy"] == b and r["sigma_s"] == s and
                  r["g"] == g and r["metric"] == metric and r["time_spp"] == top]
            cells.extend(fmt_ratio(rr[0] if rr else None))
        lines.append(f"| {b} | {s} | {g} | " + " | ".join(cells) + " |")
lines.append("\n(* extrapolated beyond the largest steady budget along slope -1.)\n")

ctop = max((r["spp"] for r in combo_rows), default=0)
lines.append(f"Every combination at {ctop} spp (sigma_s 0.9, isotropic): median frame error, "
             f"wall-clock time and efficiency 1 / (error x time) relative to steady sampling.\n")
lines.append("| distance/connection/angular[/mis] | frame relMSE | time (s) | efficiency |")
lines.append("|---|---|---|---|")
for r in sorted((r for r in combo_rows if r["spp"] == ctop),
                key=lambda r: -r["efficiency_vs_steady"] if math.isfinite(r["efficiency_vs_steady"]) else 0):
    lines.append(f"| {r['strategy']} | {r['frame_relmse']:.4g} | {r['wall_s']:.3f} | "
                 f"{r['efficiency_vs_steady']:.2f} |")

single = sorted({k[3] for k in med if k[0] == "single"})
stop = max((k[4] for k in med if k[0] == "single"), default=0)
lines.append(f"\nSingle scattering (Fig. 5.10) at {stop} spp: median errors.\n")
lines.append("| strategy | frame relMSE | pixel (a) relMSE | cube relMSE |")
lines.append("|---|---|---|---|")
for c in single:
    v = med.get(("single", 0.9, 0.0, c, stop))
    if v:
        lines.append(f"| {c} | {v['frame_relmse']:.4g} | {v['pixel_relmse']:.4g} | "
                     f"{v['cube_relmse']:.4g} |")
with open(os.path.join(RESULTS, "media_tables.md"), "w") as f:
    f.write("\n".join(lines) + "\n")
print("\n".join(lines))

# Plots.
gs = sorted({g for _, g in media})
ss = sorted({s for s, _ in media})
BUNDLES = (("steady", "tab:blue"), ("time", "tab:red"), ("time_mfp", "tab:green"))


def medium_grid(filename, panel):
    """One panel per medium (rows g, columns sigma_s), drawn by panel(ax, sigma_s, g)."""
    fig, axes = plt.subplots(len(gs), len(ss), figsize=(4 * len(ss), 3.2 * len(gs)),
                             squeeze=False)
    for i, g in enumerate(gs):
        for j, s in enumerate(ss):
            panel(axes[i][j], s, g)
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, filename), dpi=110)


def positive(t, v):
    """The (t, v) pairs with a finite, positive v (log axes)."""
    pts = [(a, b) for a, b in zip(t, v) if math.isfinite(b) and b > 0]
    return [p[0] for p in pts], [p[1] for p in pts]


def error_panel(ax, s, g):
    for strategy, colour in BUNDLES:
        for metric, style in (("frame_relmse", "-"), ("pixel_relmse", "--")):
            pts = [p for p in curve("media", s, g, strategy, metric) if p[1] > 0]
            if pts:
                ax.loglog([p[0] for p in pts], [p[1] for p in pts], style, color=colour,
                          marker="o", ms=3, label=f"{strategy} {metric.split('_')[0]}")
    ax.set_title(f"sigma_s {s}, g {g}", fontsize=9)
    ax.set_xlabel("spp")
    ax.set_ylabel("relMSE")
    ax.grid(True, which="both", alpha=0.3)


if media:
    medium_grid("media_error.png", error_panel)

fr = defaultdict(list)
for r in frames:
    fr[(r["part"], float(r["sigma_s"]), float(r["g"]), r["strategy"], int(r["spp"]))].append(r)


def series(part, s, g, strategy, spp, field):
    rows = sorted(fr.get((part, s, g, strategy, spp), []), key=lambda r: int(r["frame"]))
    return [float(r["t"]) for r in rows], [float(r[field]) for r in rows]


if media:
    mid = sorted({k[4] for k in fr if k[0] == "media"})
    spp = mid[len(mid) // 2] if mid else 0
    top_spp = max(mid) if mid else 0

    def profile_panel(ax, s, g):
        t, ref = series("media", s, g, "steady", spp, "pixel_ref")
        ax.plot(t, ref, color="black", lw=1.2, label="reference")
        for strategy, colour in BUNDLES:
            t, v = series("media", s, g, strategy, spp, "pixel")
            ax.plot(t, v, color=colour, lw=0.8, label=f"{strategy}, {spp} spp")
        ax.set_yscale("symlog", linthresh=max(1e-6, max(ref, default=1) * 1e-3))
        ax.set_title(f"pixel (a), sigma_s {s}, g {g}", fontsize=9)
        ax.set_xlabel("time (scene units)")

    def error_time_panel(ax, s, g):
        for strategy, colour in BUNDLES:
            t, v = positive(*series("media", s, g, strategy, top_spp, "frame_relmse"))
            if t:
                ax.semilogy(t, v, color=colour, label=f"{strategy}, {top_spp} spp")
        ax.set_title(f"error per frame, sigma_s {s}, g {g}", fontsize=9)
        ax.set_xlabel("time (scene units)")

    medium_grid("media_profiles.png", profile_panel)
    medium_grid("media_error_time.png", error_time_panel)

if single:
    sspp = max(k[4] for k in fr if k[0] == "single")
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.6))
    for c in single:
        t, v = positive(*series("single", 0.9, 0.0, c, sspp, "frame_relmse"))
        if t:
            a1.semilogy(t, v, label=c)
        t, n = series("single", 0.9, 0.0, c, sspp, "samples")
        total = sum(n) or 1
        a2.plot(t, [x / total for x in n], label=c)
    a1.set_title(f"single scattering: relative error per frame ({sspp} spp)", fontsize=9)
    a2.set_title("share of samples (contributions) per frame", fontsize=9)
    for a in (a1, a2):
        a.set_xlabel("time (scene units)")
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, "media_single.png"), dpi=110)

if combos:
    fig, ax = plt.subplots(figsize=(9, 6))
    cmap = plt.get_cmap("tab20")
    for idx, c in enumerate(combos):
        pts = [p for p in curve("combos", 0.9, 0.0, c, "frame_relmse") if p[1] > 0]
        if pts:
            steady = c == "mean_free_path/deterministic/phase"
            ax.loglog([p[2] for p in pts], [p[1] for p in pts], marker="o", ms=3,
                      lw=2.5 if steady else 1, color="black" if steady else cmap(idx % 20),
                      label=c)
    ax.set_xlabel("wall-clock time of the render (s)")
    ax.set_ylabel("frame relMSE (median over seeds)")
    ax.set_title("every strategy combination, sigma_s 0.9, isotropic", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(os.path.join(RESULTS, "media_combos.png"), dpi=110)
print(f"wrote media_ratio.csv, media_combos.csv, media_tables.md and plots in {RESULTS}")
