#!/usr/bin/env python3
"""Error against wall-clock time of transient_path, transient_light and transient_bdpt (issue 11).

For each scene and temporal filter, renders a reference (transient_bdpt at REF_SPP, two halves
with their own seeds, so that its per-voxel noise is known: var_r = (r1 - r2)^2 / 4 per voxel
of the mean r), then every integrator at each budget (spp) with SEEDS seeds, interleaved
(budget, seed, integrator), and records the render time femto reports (its "Rendered ... in T
s" line: the render only, no loading or writing) and its ray rate. The error is the
noise-corrected cube relMSE of bench/README.md: (sum (x - r)^2 - sum var_r) / sum r^2.

Equal-error time ratio: E is the path tracer's median error at its largest budget and t_path
its median time there; per integrator A, a line log(error) = a + b log(time) is fitted to the
per-budget medians, and A reaches E at t_A = exp((log E - a) / b) (extrapolated when E lies
outside A's range). The ratio t_path / t_A (> 1: A reaches it sooner) gets a 90 % interval from
1000 bootstrap resamples of the seeds within each budget.

Usage: bidir.py FEMTO OUT_DIR [--quick]
Writes OUT_DIR/bidir_runs.csv, bidir_ratios.csv, bidir.png.
"""
import atexit
import csv
import warnings
import math
import os
import random
import re
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
INTEGRATORS = ["transient_path", "transient_light", "transient_bdpt"]
# scene, defines, max_depth, hide_emitters, budgets (spp), reference spp. fog-object's point
# light is in view: a light tracer and BDPT splat it onto one pixel, which a path tracer never
# sees, so emitters seen directly are hidden there for all three.
SCENES = [
    ("caustic", {"res": "32"}, 6, False, [16, 32, 64, 128, 256], 8192),
    ("cornell-box", {"res": "32"}, 8, False, [8, 16, 32, 64, 128], 4096),
    ("fog-object", {"res": "32", "bins": "80"}, 8, True, [16, 32, 64, 128, 256], 8192),
]
FILTERS = {
    "histogram": '<tfilter type="histogram"/>',
    "kernel": '<tfilter type="kernel"/>',
}
SEEDS = 3


def scene_xml(name, integrator, max_depth, hide, tfilter):
    text = open(os.path.join(ROOT, "scenes", name, "scene.xml")).read()
    a = text.index("<integrator")
    b = text.index("</integrator>") + len("</integrator>")
    text = (text[:a] + f'<integrator type="{integrator}"><integer name="max_depth" '
            f'value="{max_depth}"/><boolean name="hide_emitters" '
            f'value="{"true" if hide else "false"}"/></integrator>' + text[b:])
    text, n = re.subn(r'<tfilter type="[^"]*"\s*/>', FILTERS[tfilter], text, count=1)
    if n != 1:
        raise SystemExit(f"{name}: no <tfilter .../> to replace")
    return text


def render(femto, xml_path, defines, spp, seed, out):
    cmd = [femto, "render", xml_path, "-o", out, "--npy", "--seed", str(seed), "-D",
           f"spp={spp}"]
    for k, v in defines.items():
        cmd += ["-D", f"{k}={v}"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"femto failed ({p.returncode}): {' '.join(cmd)}\n{p.stderr}")
    m = re.search(r"Rendered \d+ of \d+ spp in ([0-9.]+) s \(([0-9.]+) M rays/s\)",
                  p.stderr.replace("\r", "\n"))
    if not m:
        sys.exit(f"no render time in femto's output:\n{p.stderr}")
    return float(m.group(1)), float(m.group(2)), np.load(out + ".npy").astype(np.float64)


def fit(times, errors, budgets=None):
    """log(error) = a + b log(time), least squares; with `budgets`, over the medians of log
    time and log error per budget (robust to the rare fireflies that dominate single runs)."""
    lt, le = np.log(times), np.log(errors)
    if budgets is not None:
        keys = sorted(set(budgets))
        lt = np.array([np.median(lt[np.array(budgets) == k]) for k in keys])
        le = np.array([np.median(le[np.array(budgets) == k]) for k in keys])
    b, a = np.polyfit(lt, le, 1)
    return a, b


def time_at(a, b, error):
    return math.exp((math.log(error) - a) / b)


def option(name, default=None):
    """The value after `name` on the command line (e.g. --budgets 64,128), or `default`."""
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


def main():
    warnings.simplefilter("ignore", np.RankWarning)  # bootstrap resamples of few distinct runs
    femto, out_dir = sys.argv[1], sys.argv[2]
    quick = "--quick" in sys.argv
    # One scene / filter at other budgets, into files of their own (e.g. --scene cornell-box
    # --tfilter kernel --budgets 64,128,256,512,1024 --prefix bidir_cornell_kernel).
    only_scene, only_filter = option("--scene"), option("--tfilter")
    budgets_option, ref_option = option("--budgets"), option("--ref-spp")
    prefix = option("--prefix", "bidir")
    os.makedirs(out_dir, exist_ok=True)
    work = tempfile.mkdtemp()
    runs_csv = open(os.path.join(out_dir, f"{prefix}_runs.csv"), "w", newline="")
    runs = csv.writer(runs_csv)
    runs.writerow(["scene", "tfilter", "integrator", "spp", "seed", "seconds", "mrays_per_s",
                   "cube_relmse"])
    ratio_rows = []
    results = {}
    for scene, defines, depth, hide, budgets, ref_spp in SCENES:
        if only_scene and scene != only_scene:
            continue
        if quick:
            budgets, ref_spp = budgets[:2], 256
        if budgets_option:
            budgets = [int(b) for b in budgets_option.split(",")]
        if ref_option:
            ref_spp = int(ref_option)
        for tfilter in FILTERS:
            if only_filter and tfilter != only_filter:
                continue
            xml = {}
            for integ in INTEGRATORS:
                # Next to the scene: it includes files by paths relative to its folder.
                xml[integ] = os.path.join(ROOT, "scenes", scene,
                                          f".bidir-{os.getpid()}-{tfilter}-{integ}.xml")
                atexit.register(lambda path=xml[integ]: os.path.exists(path) and os.remove(path))
                open(xml[integ], "w").write(scene_xml(scene, integ, depth, hide, tfilter))
            halves = [render(femto, xml["transient_bdpt"], defines, ref_spp // 2, 1000 + h,
                             os.path.join(work, f"ref{h}"))[2] for h in (1, 2)]
            ref = (halves[0] + halves[1]) / 2
            ref_var = ((halves[0] - halves[1]) ** 2 / 4).sum()
            norm = (ref ** 2).sum()
            print(f"{scene}/{tfilter}: reference noise {ref_var / norm:.3g}", flush=True)
            for spp in budgets:
                for seed in range(1, SEEDS + 1):
                    for integ in INTEGRATORS:
                        t, rate, x = render(femto, xml[integ], defines, spp, seed,
                                            os.path.join(work, "x"))
                        err = ((x - ref) ** 2).sum() - ref_var
                        err = max(err, 1e-3 * ref_var) / norm
                        runs.writerow([scene, tfilter, integ, spp, seed, t, rate, err])
                        runs_csv.flush()
                        results.setdefault((scene, tfilter, integ), []).append(
                            (t, err, rate, spp))
                        print(f"  {integ:16s} spp {spp:4d} seed {seed}: {t:7.2f} s "
                              f"relMSE {err:.3e} ({rate:.2f} Mrays/s)", flush=True)
            ratio_rows += equal_error_ratios(scene, tfilter, results)
    runs_csv.close()
    with open(os.path.join(out_dir, f"{prefix}_ratios.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["scene", "tfilter", "integrator", "slope", "target_relmse",
                    "time_ratio_vs_path", "ratio_p05", "ratio_p95", "mrays_per_s_median",
                    "ray_rate_vs_path"])
        w.writerows(ratio_rows)
    plot(results, os.path.join(out_dir, f"{prefix}.png"))


def resample(runs, rng):
    """The runs resampled with replacement within each budget."""
    by_budget = {}
    for r in runs:
        by_budget.setdefault(r[3], []).append(r)
    return [rng.choice(group) for group in by_budget.values() for _ in group]


def ratio_of(path, runs):
    largest = max(r[3] for r in path)
    top = [r for r in path if r[3] == largest]
    target = float(np.median([r[1] for r in top]))
    t_path = float(np.median([r[0] for r in top]))
    a, b = fit([r[0] for r in runs], [r[1] for r in runs], [r[3] for r in runs])
    if not b < 0:
        return target, b, float("nan")
    return target, b, t_path / time_at(a, b, target)


def equal_error_ratios(scene, tfilter, results):
    rng = random.Random(7)
    path = results[(scene, tfilter, "transient_path")]
    path_rate = float(np.median([r[2] for r in path]))
    rows = []
    for integ in INTEGRATORS:
        runs = results[(scene, tfilter, integ)]
        target, b, ratio = ratio_of(path, runs)
        boot = []
        for _ in range(1000):
            _, _, r = ratio_of(resample(path, rng), resample(runs, rng))
            if math.isfinite(r):
                boot.append(r)
        boot.sort()
        lo = boot[int(0.05 * len(boot))] if boot else float("nan")
        hi = boot[int(0.95 * len(boot)) - 1] if boot else float("nan")
        rate = float(np.median([r[2] for r in runs]))
        rows.append([scene, tfilter, integ, f"{b:.3f}", f"{target:.4g}", f"{ratio:.3g}",
                     f"{lo:.3g}", f"{hi:.3g}", f"{rate:.3f}", f"{rate / path_rate:.3f}"])
        print(f"{scene}/{tfilter} {integ}: slope {b:.2f}, equal-error time ratio vs path "
              f"{ratio:.3g} [{lo:.3g}, {hi:.3g}], rays/s {rate / path_rate:.2f}x path", flush=True)
    return rows


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    keys = sorted({(s, f) for s, f, _ in results})
    fig, axes = plt.subplots(1, len(keys), figsize=(4 * len(keys), 3.6), squeeze=False)
    for ax, (scene, tfilter) in zip(axes[0], keys):
        for integ in INTEGRATORS:
            runs = results.get((scene, tfilter, integ), [])
            if not runs:
                continue
            t = [r[0] for r in runs]
            e = [r[1] for r in runs]
            pts = ax.loglog(t, e, "o", ms=3, label=integ.replace("transient_", ""))
            a, b = fit(t, e, [r[3] for r in runs])
            xs = np.array([min(t), max(t)])
            ax.loglog(xs, np.exp(a) * xs ** b, "-", color=pts[0].get_color(), lw=1)
        ax.set_title(f"{scene} / {tfilter}", fontsize=9)
        ax.set_xlabel("render time (s)")
        ax.set_ylabel("cube relMSE")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
