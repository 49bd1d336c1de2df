#!/usr/bin/python3
"""Plots and tables for femto_bench_kernel (bench/kernel.cpp): error against time of the
`kernel` temporal filter next to the histogram.

    /usr/bin/python3 bench/plot_kernel.py [RESULTS_DIR]      (default bench/results)

Reads kernel_error.csv, kernel_profiles.csv and kernel_scenes.csv; writes
  kernel_speedup.csv   for every kernel variant, scene, metric and budget: the median time and
                       error of the kernel, the time the histogram needs for that error (log-log
                       interpolation of the histogram's medians; beyond them, extrapolation along
                       the histogram's fitted slope, flagged) and their ratio (the speed-up);
  kernel_slopes.csv    least-squares slopes of log(error) against log(time) of the medians, over
                       all budgets and over the budgets >= 128 spp;
  kernel_tables.md     the tables quoted in bench/README.md;
  kernel_error.png     error against time, histogram vs kernel, every scene and metric;
  kernel_sweep.png     the same for every variant on the sweep scenes;
  kernel_profile.png   one pixel's time profile per scene at equal spp (thesis Fig. 5.5).
"""
import csv
import math
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

METRICS = [
    ("cube_relmse", "cube relMSE"),
    ("frame_relmse", "mean per-frame relMSE"),
    ("pixel_relmse", "pixel-profile relMSE"),
]
EXTRA_METRICS = ["frame_relmse_median", "frame_relmse_all", "cube_relmse_raw"]
RESEARCH_SPP = (256, 512, 1024, 2048)  # "the budgets researchers use" (thesis: ~1K spp)
ASYMPTOTIC_SPP = 128  # slopes also over budgets >= this
PROFILE_PIXEL = {"tof-plane": 1}  # which selected pixel kernel_profile.png shows (default 0)


def median(v):
    v = sorted(v)
    n = len(v)
    if n == 0:
        return float("nan")
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def fit_slope(points):
    """Least-squares slope and intercept of log(err) over log(time); positive errors only."""
    pts = [(math.log(t), math.log(e)) for t, e in points if t > 0 and e > 0]
    if len(pts) < 2:
        return float("nan"), float("nan")
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    sxy = sum((p[0] - mx) * (p[1] - my) for p in pts)
    b = sxy / sxx if sxx > 0 else float("nan")
    return b, my - b * mx


def hist_time_for(err, curve, slope):
    """Time at which the histogram's median curve (list of (time, err), ascending time)
    reaches `err`: log-log interpolation between the two medians that bracket it; outside
    them, extrapolation from the nearest end along the fitted slope. Returns (time, how)."""
    pts = [(t, e) for t, e in curve if t > 0 and e > 0]
    if not pts or not (err > 0):
        return float("nan"), "none"
    for (t0, e0), (t1, e1) in zip(pts, pts[1:]):
        if (e0 - err) * (e1 - err) <= 0 and e0 != e1:
            a = (math.log(err) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + a * (math.log(t1) - math.log(t0))), "interpolated"
    if not (slope < 0):
        return float("nan"), "none"
    # Outside the measured range: from the end nearest in error.
    t_end, e_end = pts[-1] if err < pts[-1][1] else pts[0]
    if pts[0][1] < err and err < pts[-1][1]:  # non-monotone curve that never crosses: skip
        return float("nan"), "none"
    how = "extrapolated" if err < e_end else "extrapolated_back"
    return t_end * (err / e_end) ** (1.0 / slope), how


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "results")
    rows = read_csv(os.path.join(out, "kernel_error.csv"))
    scenes_info = {r["scene"]: r for r in read_csv(os.path.join(out, "kernel_scenes.csv"))}
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    labels = defaultdict(list)
    for r in rows:
        if r["label"] not in labels[r["scene"]]:
            labels[r["scene"]].append(r["label"])

    # Medians per (scene, label, spp) of time and every metric, plus every run for scatter.
    groups = defaultdict(list)
    for r in rows:
        groups[(r["scene"], r["label"], int(r["spp"]))].append(r)
    med = {}
    for key, rs in groups.items():
        m = {"seconds": median([float(r["seconds"]) for r in rs]), "runs": len(rs)}
        for name, _ in METRICS:
            m[name] = median([float(r[name]) for r in rs])
        for name in EXTRA_METRICS:
            if name in rs[0]:
                m[name] = median([float(r[name]) for r in rs])
        med[key] = m

    def curve(scene, label, metric, min_spp=0):
        spps = sorted(s for (sc, lb, s) in med if sc == scene and lb == label and s >= min_spp)
        return [(med[(scene, label, s)]["seconds"], med[(scene, label, s)][metric]) for s in spps], spps

    # Slopes.
    slopes = {}
    with open(os.path.join(out, "kernel_slopes.csv"), "w") as f:
        f.write("scene,label,metric,slope_all,slope_ge{}spp,budgets\n".format(ASYMPTOTIC_SPP))
        for sc in scenes:
            for lb in labels[sc]:
                for mt, _ in METRICS + [(m, m) for m in EXTRA_METRICS]:
                    if mt not in next(iter(med.values())):
                        continue
                    c, spps = curve(sc, lb, mt)
                    s_all, _ = fit_slope(c)
                    s_hi, _ = fit_slope(curve(sc, lb, mt, ASYMPTOTIC_SPP)[0])
                    slopes[(sc, lb, mt)] = (s_all, s_hi)
                    f.write(f"{sc},{lb},{mt},{s_all:.3f},{s_hi:.3f},{len(spps)}\n")

    # Equal-error speed-ups.
    speed = {}
    with open(os.path.join(out, "kernel_speedup.csv"), "w") as f:
        f.write("scene,label,metric,spp,kernel_seconds,kernel_error,histogram_seconds_same_error,"
                "speedup,how\n")
        for sc in scenes:
            for mt, _ in METRICS:
                hc, _ = curve(sc, "histogram", mt)
                hslope = slopes[(sc, "histogram", mt)][0]
                for lb in labels[sc]:
                    if lb == "histogram":
                        continue
                    kc, spps = curve(sc, lb, mt)
                    for (t, e), spp in zip(kc, spps):
                        th, how = hist_time_for(e, hc, hslope)
                        sp = th / t if th == th else float("nan")
                        speed[(sc, lb, mt, spp)] = (sp, how)
                        f.write(f"{sc},{lb},{mt},{spp},{t:.5f},{e:.6g},{th:.5f},{sp:.4g},{how}\n")

    # Tables (markdown).
    def fmt_sp(sc, lb, mt, spp):
        sp, how = speed.get((sc, lb, mt, spp), (float("nan"), "none"))
        if sp != sp:
            return "—"
        s = f"{sp:.2f}" if sp < 10 else f"{sp:.0f}"
        return s + ("*" if how.startswith("extrapolated") else "")

    md = []
    md.append("Equal-error speed-up = (time the histogram needs for the kernel's median error) / "
              "(kernel's median time); > 1: the kernel is faster. * = the histogram's time is "
              "extrapolated along its fitted slope (the kernel's error lies outside the "
              "histogram's measured range). Errors are noise-corrected (the reference's "
              "variance removed) relative MSEs, medians over seeds; times are wall-clock "
              "seconds of the render (the kernel's pilot pass included).\n")
    for sc in scenes:
        info = scenes_info.get(sc, {})
        md.append(f"\n**{sc}** ({info.get('res', '?')}² px, {info.get('bins', '?')} bins of "
                  f"{info.get('bin_width', '?')}, {info.get('sampler', '?')}; reference "
                  f"{info.get('ref_spp', '?')} spp)\n")
        md.append("| spp | hist s | kernel s | hist cube | kernel cube | **speed-up cube** | "
                  "hist frame | kernel frame | **speed-up frame** | hist pixel | kernel pixel | "
                  "**speed-up pixel** |")
        md.append("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        spps = sorted(s for (s_, lb, s) in med if s_ == sc and lb == "histogram")
        for spp in spps:
            h = med[(sc, "histogram", spp)]
            k = med.get((sc, "kernel", spp))
            if not k:
                continue
            md.append(
                f"| {spp} | {h['seconds']:.3f} | {k['seconds']:.3f} | "
                f"{h['cube_relmse']:.3g} | {k['cube_relmse']:.3g} | "
                f"**{fmt_sp(sc, 'kernel', 'cube_relmse', spp)}** | "
                f"{h['frame_relmse']:.3g} | {k['frame_relmse']:.3g} | "
                f"**{fmt_sp(sc, 'kernel', 'frame_relmse', spp)}** | "
                f"{h['pixel_relmse']:.3g} | {k['pixel_relmse']:.3g} | "
                f"**{fmt_sp(sc, 'kernel', 'pixel_relmse', spp)}** |")
    md.append("\nFitted slopes d log(error) / d log(time) of the medians (all budgets; "
              f"budgets >= {ASYMPTOTIC_SPP} spp in brackets):\n")
    md.append("| scene | variant | cube relMSE | frame relMSE | pixel relMSE |")
    md.append("|---|---|---:|---:|---:|")
    for sc in scenes:
        for lb in labels[sc]:
            cells = []
            for mt, _ in METRICS:
                a, b = slopes[(sc, lb, mt)]
                cells.append(f"{a:.2f} ({b:.2f})")
            md.append(f"| {sc} | {lb} | " + " | ".join(cells) + " |")
    sweep_scenes = [sc for sc in scenes if len(labels[sc]) > 2]
    for sc in sweep_scenes:
        md.append(f"\nVariants on **{sc}**: equal-error speed-up over the histogram per budget "
                  "(cube / frame / pixel metric):\n")
        spps = sorted(s for (s_, lb, s) in med if s_ == sc and lb == "histogram")
        md.append("| variant | " + " | ".join(f"{s} spp" for s in spps) + " |")
        md.append("|---|" + "---:|" * len(spps))
        for lb in labels[sc]:
            if lb == "histogram":
                continue
            cells = [" / ".join(fmt_sp(sc, lb, mt, s) for mt, _ in METRICS) for s in spps]
            md.append(f"| {lb} | " + " | ".join(cells) + " |")
        md.append(f"\nVariants on **{sc}**: median errors at 64 and 1024 spp (cube / frame / "
                  "pixel metric) and the geometric mean of the speed-ups at "
                  f"{'-'.join(str(s) for s in (RESEARCH_SPP[0], RESEARCH_SPP[-1]))} spp:\n")
        md.append("| variant | 64 spp | 1024 spp | geo-mean speed-up, cube | frame | pixel |")
        md.append("|---|---|---|---:|---:|---:|")
        for lb in labels[sc]:
            cells = []
            for s in (64, 1024):
                m = med.get((sc, lb, s))
                cells.append(" / ".join(f"{m[mt]:.3g}" for mt, _ in METRICS) if m else "—")
            gm = []
            for mt, _ in METRICS:
                v = [speed.get((sc, lb, mt, s), (float("nan"),))[0] for s in RESEARCH_SPP]
                v = [x for x in v if x == x and x > 0]
                gm.append(f"{math.exp(sum(map(math.log, v)) / len(v)):.2f}" if v and lb != "histogram" else "—")
            md.append(f"| {lb} | " + " | ".join(cells) + " | " + " | ".join(gm) + " |")
    with open(os.path.join(out, "kernel_tables.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    print("\n".join(md))

    # kernel_error.png: scenes x metrics, histogram vs kernel.
    colours = {"histogram": "tab:red", "kernel": "tab:blue"}
    fig, axes = plt.subplots(len(scenes), len(METRICS), figsize=(4.6 * len(METRICS), 3.6 * len(scenes)),
                             squeeze=False)
    for i, sc in enumerate(scenes):
        for j, (mt, title) in enumerate(METRICS):
            ax = axes[i][j]
            for lb in ("histogram", "kernel"):
                xs = [float(r["seconds"]) for r in rows if r["scene"] == sc and r["label"] == lb]
                ys = [float(r[mt]) for r in rows if r["scene"] == sc and r["label"] == lb]
                ax.scatter(xs, [y if y > 0 else float("nan") for y in ys], s=6, alpha=0.3,
                           color=colours[lb])
                c, spps = curve(sc, lb, mt)
                s_all = slopes[(sc, lb, mt)][0]
                ax.plot([t for t, _ in c], [e if e > 0 else float("nan") for _, e in c], "o-",
                        color=colours[lb], ms=4, label=f"{lb} (slope {s_all:.2f})")
                if lb == "histogram":
                    for (t, e), s in zip(c, spps):
                        if e > 0:
                            ax.annotate(str(s), (t, e), fontsize=6, color="grey",
                                        xytext=(2, 2), textcoords="offset points")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.grid(True, which="both", alpha=0.3)
            ax.set_title(f"{sc}: {title}", fontsize=9)
            ax.set_xlabel("render time (s, wall clock, 2 threads)")
            ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "kernel_error.png"), dpi=110)
    plt.close(fig)

    # kernel_sweep.png: every variant on the sweep scenes.
    if sweep_scenes:
        fig, axes = plt.subplots(len(sweep_scenes), len(METRICS),
                                 figsize=(4.6 * len(METRICS), 3.8 * len(sweep_scenes)), squeeze=False)
        cmap = plt.get_cmap("tab10")
        for i, sc in enumerate(sweep_scenes):
            for j, (mt, title) in enumerate(METRICS):
                ax = axes[i][j]
                for n, lb in enumerate(labels[sc]):
                    c, _ = curve(sc, lb, mt)
                    style = "o-" if lb in ("histogram", "kernel") else ".--"
                    colour = colours.get(lb, cmap((n + 2) % 10))
                    ax.plot([t for t, _ in c], [e if e > 0 else float("nan") for _, e in c], style,
                            color=colour, ms=4, lw=1.6 if lb in colours else 1.0, label=lb)
                ax.set_xscale("log")
                ax.set_yscale("log")
                ax.grid(True, which="both", alpha=0.3)
                ax.set_title(f"{sc}: {title}", fontsize=9)
                ax.set_xlabel("render time (s)")
                ax.legend(fontsize=6, ncol=2)
        fig.tight_layout()
        fig.savefig(os.path.join(out, "kernel_sweep.png"), dpi=110)
        plt.close(fig)

    # kernel_profile.png: Fig. 5.5 - one pixel's time profile per scene at equal spp.
    prof_path = os.path.join(out, "kernel_profiles.csv")
    if os.path.exists(prof_path):
        prof = defaultdict(list)
        with open(prof_path) as f:
            for r in csv.DictReader(f):
                prof[(r["scene"], r["label"], int(r["spp"]), r["x"], r["y"])].append(
                    (int(r["bin"]), float(r["value"]), float(r["sd"])))
        show_spp = [32, 512]
        fig, axes = plt.subplots(len(scenes), len(show_spp), figsize=(6.2 * len(show_spp), 3.2 * len(scenes)),
                                 squeeze=False)
        for i, sc in enumerate(scenes):
            info = scenes_info[sc]
            start, bw = float(info["start"]), float(info["bin_width"])
            # One of the selected pixels (in the order the benchmark wrote them): on the
            # tof-plane the second, off-centre one, whose arrival spans several bins.
            refkeys = [k for k in prof if k[0] == sc and k[1] == "reference"]
            if not refkeys:
                continue
            pick = refkeys[min(PROFILE_PIXEL.get(sc, 0), len(refkeys) - 1)]
            x, y = pick[3], pick[4]
            ref = sorted(prof.get((sc, "reference", int(info["ref_spp"]), x, y), []))
            # Show the part of the window where the reference has signal.
            nz = [b for b, v, _ in ref if v > 0]
            vmax = max((v for _, v, _ in ref), default=0)
            nz = [b for b, v, _ in ref if v > 0.02 * vmax]  # where the profile matters
            lo, hi = (max(0, min(nz) - 5), max(nz) + 8) if nz else (0, len(ref))
            for j, spp in enumerate(show_spp):
                ax = axes[i][j]
                ts = [start + (b + 0.5) * bw for b, _, _ in ref]
                ax.fill_between(ts, [v - sd for _, v, sd in ref], [v + sd for _, v, sd in ref],
                                color="k", alpha=0.15, lw=0, step="mid")
                ax.step(ts, [v for _, v, _ in ref], "k-", where="mid", lw=1.2,
                        label=f"reference ({info['ref_spp']} spp, ±1 sd)")
                for lb in ("histogram", "kernel"):
                    p = sorted(prof.get((sc, lb, spp, x, y), []))
                    if not p:
                        continue
                    t_med = med[(sc, lb, spp)]["seconds"]
                    ax.step([start + (b + 0.5) * bw for b, _, _ in p], [v for _, v, _ in p],
                            where="mid", color=colours[lb], lw=0.9,
                            label=f"{lb} ({spp} spp, {t_med:.2f} s)")
                ax.set_xlim(start + lo * bw, start + min(hi, len(ref)) * bw)
                ax.set_title(f"{sc}, pixel ({x}, {y}), {spp} spp", fontsize=9)
                ax.set_xlabel("camera time (optical path length, scene units)")
                ax.set_ylabel("radiance (RGB mean)")
                ax.legend(fontsize=7)
                ax.grid(True, alpha=0.3)
        fig.tight_layout()
        fig.savefig(os.path.join(out, "kernel_profile.png"), dpi=110)
        plt.close(fig)
    print(f"\nwrote kernel_speedup.csv, kernel_slopes.csv, kernel_tables.md, kernel_*.png in {out}")


if __name__ == "__main__":
    main()
