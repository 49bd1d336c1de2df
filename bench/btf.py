#!/usr/bin/env python3
"""Prefiltered BTF rendering against multisampling (issue 16 §4; Jarabo, Plenoptic Light
Transport, 2015, ch. 3, Experiment 1) on scenes/btf-sphere.

For each distance d0..d4 (a texel-to-pixel ratio r = 1, 4, 16, 64, 256 at the centre of the
view), at RES x RES pixels with the camera moved so that r stays what it is at res 512
(d = R + r * RES / (T * 2 tan 15 deg), T = 128 * 64 / (2 pi) texels per unit length, see
scenes/btf-sphere/scene.xml), renders

  (a) a reference: the unfiltered BTF (prefilter false) at REF_SPP samples per pixel, as two
      halves with their own seeds, so that its own noise is known per pixel and channel
      (var_r = (h1 - h2)^2 / 4 for the mean r) and subtracted from every squared error;
  (b) the unfiltered BTF multisampled at N = 1, 2, 4, ..., 256 spp;
  (c) the prefiltered BTF at 1 spp for every filter (box, gaussian, lanczos) and scale s
      (0.5, 1, 2: scale_spatial = scale_light = scale_view = s), each with the mip-map's
      level (spatial_lookup mipmap, the thesis' lookup) and with the exact box over the
      pixel's footprint (spatial_lookup footprint; configurations named "box-footprint" etc.),
      and the footprint box with one ray through each pixel's centre ("box-footprint-centre":
      `stratified` without jitter, where the others take ldsampler's jittered sample),

all with `ldsampler` (Owen-scrambled (0,2)-sequence; complete nets at powers of two; the
"-centre" configurations aside), a box
pixel filter and the `direct` integrator; (b) and (c) RUNS times each with seeds 1..RUNS.

Errors against the reference, per render:
  rmse         sqrt(mean over pixels and RGB channels of (x - r)^2 - var_r), the whole image
               (black background included);
  rmse_inner   the same over the pixels that the reference's lit area holds with all 8
               neighbours (the silhouette and the terminator excluded);
  ssim         skimage.metrics.structural_similarity on luminance (Rec. 709 Y), data range
               the reference's maximum luminance, default 7 x 7 window.
The time is femto's own "Rendered ... in T s" line (the render alone: no loading, no
hierarchy build, no writing), printed to 0.01 s (0.00 counts as 0.005 s). A configuration's error and time are the medians of its runs.

Equal-error speed-up, per distance and prefiltered configuration: the multisampled N whose
median RMSE equals the prefiltered median RMSE, interpolated log-log between the bracketing N
(the multisampled time interpolated log-log between the same N), and t_ms(N) / t_pf. Beyond
N = 256 the multisampled curve is extrapolated with the log-log slope of its last four points
(time linearly in N) and the row is flagged; a prefiltered error above the multisampled
error at N = 1 gets t_ms(1) / t_pf, flagged.

Hierarchy build time and size: `femto btf info --prefilter --no-cache --filter F` (its
"built in T s" and size), median of RUNS, and the size of the cache file it writes.

The same speed-ups on the inner pixels' RMSE (rmse_inner) are in speedup_inner: at the far
distances a 1-spp render's silhouette, which no prefiltering antialiases, dominates the whole
image's error. At d3 and d4 a 1-spp render takes 0.01 s, femto's printed resolution; --cost
measures each mode's time per sample from renders of 64 spp (btf_cost.csv), and
speedup_by_cost = N_equal / (a prefiltered sample's time / an unfiltered sample's time).

BTF A (--btf a, the default) is scenes/btf-sphere/btf-a.btf; BTF B (--btf b) is made at bench
time in the temporary folder by `femto btf synth --kind vgroove --format dfmf --half --width 64
--height 32` (3.4 MB, not in the source tree; 64 x 32 texels like A, so d0..d4 keep their r) and
passed to the scene as -D btf=... . B's hierarchy takes ~5-8 s to build (A's 0.2 s), so with B
the material caches it (cache true) next to the generated file: the first render of each filter
builds it, the others load it. The times measured are the renders' alone either way.

Usage: btf.py FEMTO OUT_DIR [--btf a|b] [--res 128] [--ref-spp 4096] [--runs 3] [--max-spp 256]
                            [--threads N] [--quick]
       btf.py FEMTO OUT_DIR --analyse     the speed-ups and the plot again from btf_runs.csv
       btf.py FEMTO OUT_DIR --cost [--btf a|b] [--res 128] [--runs 3]   the time per sample, btf_cost.csv
       btf.py FEMTO OUT_DIR --bound [--btf a|b] [--res 128] [--ref-spp 4096] [--runs 3]
                                          the speed-up no prefiltering can exceed, btf_bound.csv
Writes OUT_DIR/btf_runs.csv, btf_speedup.csv, btf_build.csv, btf.png.
"""
import csv
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np
import tifffile
from scipy import ndimage
from skimage.metrics import structural_similarity

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE_DIR = os.path.join(ROOT, "scenes", "btf-sphere")
BTF_A = os.path.join(SCENE_DIR, "btf-a.btf")
# BTF B: Lambertian V-grooves (period 4 texels) with self-shadowing and masking, 64 x 32 texels.
SYNTH_B = ["btf", "synth", "--kind", "vgroove", "--format", "dfmf", "--half", "--width", "64",
           "--height", "32"]
RATIOS = [1, 4, 16, 64, 256]  # r at d0..d4
RADIUS = 1.0
TEXELS_PER_UNIT = 128 * 64 / (2 * math.pi * RADIUS)  # uv_scale * width / (2 pi R)
FOV = 30.0
FILTERS = ["box", "gaussian", "lanczos"]
# The prefiltered configurations' names: the pyramid's kernel; with "-footprint" the exact box
# over the pixel's footprint (spatial_lookup footprint) in place of the mip-map's level; with
# "-centre" one ray through each pixel's centre (`stratified` without jitter) in place of
# ldsampler's jittered sample.
CONFIGS = (FILTERS + [f + "-footprint" for f in FILTERS] +
           [f + "-footprint-centre" for f in FILTERS])
CENTRE_SAMPLER = ('<sampler type="stratified"><integer name="sample_count" value="$spp"/>'
                  '<boolean name="jitter" value="false"/></sampler>')


def config_defines(name):
    """The scene parameters of a prefiltered configuration's name."""
    kernel = name.partition("-")[0]
    return {"prefilter": "true", "filter": kernel,
            "lookup": "footprint" if "-footprint" in name else "mipmap"}


def through_centres(text):
    """Scene text with its ldsampler replaced by one ray through each pixel's centre."""
    text, n = re.subn(r'<sampler type="ldsampler">.*?</sampler>', CENTRE_SAMPLER, text,
                      flags=re.S)
    assert n == 1
    return text


def scene_files(work, dname, dist, btf, cache):
    """The scene at `dist` as written to WORK: (with ldsampler, through pixel centres)."""
    xml = os.path.join(work, f"btf-sphere-{dname}.xml")
    text = scene_xml(dist, btf, cache)
    open(xml, "w").write(text)
    centre = os.path.join(work, f"btf-sphere-{dname}-centre.xml")
    open(centre, "w").write(through_centres(text))
    return xml, centre
SCALES = ["0.5", "1", "2"]


def option(name, default=None):
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


def camera_distance(r, res):
    """The camera's distance from the sphere's centre at which a pixel at the centre of the
    view covers r texels."""
    return RADIUS + r * res / (TEXELS_PER_UNIT * 2 * math.tan(math.radians(FOV / 2)))


def btf_file(femto, work):
    """The BTF (--btf a or b) as an absolute path, and whether the material should cache its
    hierarchy: A is the scene's file; B is made in WORK."""
    which = option("--btf", "a")
    if which == "a":
        return BTF_A, False
    if which != "b":
        sys.exit(f"--btf {which}: a or b")
    path = os.path.join(work, "btf-b.btf")
    subprocess.run([femto, *SYNTH_B, "-o", path], capture_output=True, text=True, check=True)
    return path, True


def scene_xml(distance, btf, cache=False):
    """scenes/btf-sphere/scene.xml with the camera at `distance` (distance-dK.xml's sensor,
    moved), the BTF parameter's default the absolute path BTF, and the hierarchy cached next to
    the BTF if CACHE."""
    text = open(os.path.join(SCENE_DIR, "scene.xml")).read()
    sensor = open(os.path.join(SCENE_DIR, "distance-d0.xml")).read()
    sensor = sensor[sensor.index("<sensor"):sensor.index("</sensor>") + len("</sensor>")]
    sensor, n = re.subn(r'origin="0, -[0-9.]+, 0"', f'origin="0, -{distance:.6f}, 0"', sensor)
    assert n == 1
    include = '<include filename="distance-$distance.xml"/>'
    assert include in text
    default = '<default name="btf" value="btf-a.btf"/>'
    assert default in text
    text = text.replace(include, sensor).replace(default, f'<default name="btf" value="{btf}"/>')
    if cache:
        no_cache = '<boolean name="cache" value="false"/>'
        assert no_cache in text
        text = text.replace(no_cache, '<boolean name="cache" value="true"/>')
    return text.replace('<default name="distance" value="d2"/>', "")


def mask_xml(distance, btf):
    """scene_xml with the sphere turned into a black emitter of radiance 1 and no light: a
    pixel's value is the fraction of it that the sphere covers (at 1 spp: whether the camera
    sample hits it, with the same camera samples as the BTF renders of the same seed)."""
    text = scene_xml(distance, btf)
    start, end = text.index('<bsdf type="btf">'), text.index("</bsdf>") + len("</bsdf>")
    text = (text[:start] + '<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>'
            '<emitter type="area"><rgb name="radiance" value="1"/></emitter>' + text[end:])
    start, end = text.index('<emitter type="directional">'), text.index("</scene>")
    return text[:start] + text[end:]


def render(femto, xml, defines, seed, out, threads):
    cmd = [femto, "render", xml, "-o", out, "--seed", str(seed)]
    if threads:
        cmd += ["--threads", str(threads)]
    for k, v in defines.items():
        cmd += ["-D", f"{k}={v}"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"femto failed ({p.returncode}): {' '.join(cmd)}\n{p.stderr}")
    err = p.stderr.replace("\r", "\n")
    m = re.search(r"Rendered \d+ of \d+ spp in ([0-9.]+) s", err)
    if not m:
        sys.exit(f"no render time in femto's output:\n{p.stderr}")
    if "refused" in err:
        print(f"  warning: {err.strip().splitlines()[-1]}", flush=True)
    subprocess.run(["oiiotool", out + ".exr", "-d", "float", "--compression", "none", "-o",
                    out + ".tif"], check=True)
    # femto prints the time to 0.01 s: a render printed as 0.00 s counts as 0.005 s.
    return max(float(m.group(1)), 0.005), tifffile.imread(out + ".tif")[..., :3].astype(np.float64)


def luminance(img):
    return img @ np.array([0.2126, 0.7152, 0.0722])


class Reference:
    def __init__(self, halves):
        self.image = (halves[0] + halves[1]) / 2
        self.var = (halves[0] - halves[1]) ** 2 / 4  # per pixel and channel, of the mean
        lit = luminance(self.image) > 0
        self.inner = ndimage.binary_erosion(lit, structure=np.ones((3, 3)))
        self.y = luminance(self.image)
        self.range = float(self.y.max())

    def errors(self, x):
        d2 = (x - self.image) ** 2 - self.var
        rmse = math.sqrt(max(float(d2.mean()), 0.0))
        inner = d2[self.inner]
        rmse_inner = math.sqrt(max(float(inner.mean()), 0.0)) if inner.size else float("nan")
        ssim = structural_similarity(luminance(x), self.y, data_range=self.range)
        return rmse, rmse_inner, float(ssim)


def loglog(x0, x1, y0, y1, x):
    t = (math.log(x) - math.log(x0)) / (math.log(x1) - math.log(x0))
    return math.exp(math.log(y0) + t * (math.log(y1) - math.log(y0)))


def equal_error(ms, e_pf):
    """(N, t_ms(N), flag) at which the multisampled medians {N: (rmse, t)} reach e_pf."""
    ns = sorted(ms)
    e = [ms[n][0] for n in ns]
    t = [ms[n][1] for n in ns]
    if e_pf >= e[0]:
        return 1.0, t[0], "prefiltered error above the multisampled error at N = 1"
    for i in range(len(ns) - 1):
        if e[i] >= e_pf >= e[i + 1] and e[i + 1] > 0:
            n = loglog(e[i], e[i + 1], ns[i], ns[i + 1], e_pf)
            return n, loglog(ns[i], ns[i + 1], t[i], t[i + 1], n), ""
    # Below every multisampled error (or a non-monotone tail): extrapolate.
    k = min(4, len(ns))
    ln, le = np.log(ns[-k:]), np.log(np.maximum(e[-k:], 1e-30))
    slope, icpt = np.polyfit(ln, le, 1)
    if not slope < 0:
        return float("nan"), float("nan"), "multisampled error does not fall: no equal error"
    n = math.exp((math.log(e_pf) - icpt) / slope)
    tb, ta = np.polyfit(ns, t, 1)
    return n, ta + tb * n, f"extrapolated (log-log slope {slope:.2f} over N = {ns[-k]}..{ns[-1]})"


def hierarchy_costs(femto, runs, work, btf):
    rows = []
    work = os.path.join(work, "hierarchy")  # its own folder: the cache files it writes and removes
    os.makedirs(work)
    copy = os.path.join(work, os.path.basename(btf))
    shutil.copy(btf, copy)
    for f in FILTERS:
        times, size_mb = [], None
        for _ in range(runs):
            p = subprocess.run([femto, "btf", "info", "--prefilter", "--no-cache", "--filter", f,
                                btf], capture_output=True, text=True, check=True)
            m = re.search(r"prefilter:.*, ([0-9.]+) MB, built in ([0-9.]+) s", p.stdout)
            size_mb = float(m.group(1))
            times.append(float(m.group(2)))
        for old in os.listdir(work):
            if ".femto-prefilter-" in old:
                os.remove(os.path.join(work, old))
        subprocess.run([femto, "btf", "info", "--prefilter", "--filter", f, copy],
                       capture_output=True, text=True, check=True)
        caches = [c for c in os.listdir(work) if ".femto-prefilter-" in c]
        cache_bytes = os.path.getsize(os.path.join(work, caches[0])) if caches else 0
        rows.append([f, f"{float(np.median(times)):.3f}", f"{size_mb:.1f}", cache_bytes])
        print(f"hierarchy {f}: built in {np.median(times):.3f} s (median of {runs}), "
              f"{size_mb} MB as femto reports it, cache file {cache_bytes} bytes", flush=True)
    return rows


def main():
    femto, out_dir = sys.argv[1], sys.argv[2]
    if "--analyse" in sys.argv:  # the speed-ups and the plot again from btf_runs.csv
        summarise(out_dir)
        return
    if "--cost" in sys.argv:
        cost(femto, out_dir, int(option("--res", "128")), int(option("--runs", "3")),
             option("--threads"))
        summarise(out_dir)
        return
    if "--bound" in sys.argv:
        bound(femto, out_dir, int(option("--res", "128")), int(option("--ref-spp", "4096")),
              int(option("--runs", "3")), option("--threads"))
        return
    quick = "--quick" in sys.argv
    res = int(option("--res", "32" if quick else "128"))
    ref_spp = int(option("--ref-spp", "256" if quick else "4096"))
    runs = int(option("--runs", "1" if quick else "3"))
    max_spp = int(option("--max-spp", "16" if quick else "256"))
    threads = option("--threads")
    budgets = [2 ** k for k in range(int(math.log2(max_spp)) + 1)]
    os.makedirs(out_dir, exist_ok=True)
    work = tempfile.mkdtemp()
    btf, cache = btf_file(femto, work)
    print(f"BTF {btf}", flush=True)
    print(f"res {res}, reference {ref_spp} spp (two halves), multisampled N = {budgets}, "
          f"{runs} runs per configuration", flush=True)

    build_rows = hierarchy_costs(femto, runs, work, btf)
    with open(os.path.join(out_dir, "btf_build.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["filter", "build_seconds", "hierarchy_mb", "cache_file_bytes"])
        w.writerows(build_rows)

    runs_csv = open(os.path.join(out_dir, "btf_runs.csv"), "w", newline="")
    out_runs = csv.writer(runs_csv)
    out_runs.writerow(RUN_COLUMNS)
    for i, r in enumerate(RATIOS):
        dname, dist = f"d{i}", camera_distance(r, res)
        xml, xml_centre = scene_files(work, dname, dist, btf, cache)
        base = {"res": str(res)}
        halves = []
        for h in (1, 2):
            t, img = render(femto, xml, dict(base, prefilter="false", spp=str(ref_spp // 2)),
                            1000 + h, os.path.join(work, f"ref{h}"), threads)
            halves.append(img)
            print(f"{dname} (r {r}, camera at {dist:.4f}): reference half {h}: "
                  f"{ref_spp // 2} spp in {t:.1f} s", flush=True)
        ref = Reference(halves)
        noise = math.sqrt(float(ref.var.mean()))
        print(f"{dname}: reference noise (RMSE) {noise:.3g}, mean {ref.image.mean():.4g}, "
              f"{int(ref.inner.sum())} inner pixels", flush=True)

        def measure(mode, filt, scale, spp, defines):
            rs = []
            scene = xml_centre if filt.endswith("-centre") else xml
            for seed in range(1, runs + 1):
                t, img = render(femto, scene, dict(base, spp=str(spp), **defines), seed,
                                os.path.join(work, "x"), threads)
                e = ref.errors(img)
                out_runs.writerow([dname, r, f"{dist:.6f}", res, mode, filt, scale, spp, seed,
                                   t, f"{e[0]:.6g}", f"{e[1]:.6g}", f"{e[2]:.6f}"])
                runs_csv.flush()
                rs.append((t, *e))
            med = [float(np.median([x[k] for x in rs])) for k in range(4)]
            print(f"  {dname} {mode:12s} {filt:16s} s={scale:3s} spp {spp:4d}: {med[0]:7.3f} s "
                  f"RMSE {med[1]:.4g} (inner {med[2]:.4g}) SSIM {med[3]:.4f}", flush=True)

        for n in budgets:
            measure("multisampled", "", "", n, {"prefilter": "false"})
        for filt in CONFIGS:
            for scale in SCALES:
                measure("prefiltered", filt, scale, 1, dict(config_defines(filt), scale=scale))
    runs_csv.close()
    shutil.rmtree(work, ignore_errors=True)
    summarise(out_dir)


COST_SPP = 64


def cost(femto, out_dir, res, runs, threads):
    """The time per sample of each mode, from renders of COST_SPP samples per pixel (long
    enough that femto's 0.01 s resolution and the fixed costs do not matter): the unfiltered
    BTF and the prefiltered one per filter at s = 1, RUNS runs each, interleaved."""
    work = tempfile.mkdtemp()
    btf, cache = btf_file(femto, work)
    with open(os.path.join(out_dir, "btf_cost.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["distance", "r", "res", "mode", "filter", "spp", "seed", "seconds"])
        for i, r in enumerate(RATIOS):
            dname = f"d{i}"
            xml, xml_centre = scene_files(work, dname, camera_distance(r, res), btf, cache)
            for seed in range(1, runs + 1):
                for mode, filt in [("multisampled", "")] + [("prefiltered", x) for x in CONFIGS]:
                    defines = {"res": str(res), "spp": str(COST_SPP), "prefilter": "false"}
                    if filt:
                        defines.update(config_defines(filt))
                    scene = xml_centre if filt.endswith("-centre") else xml
                    t, _ = render(femto, scene, defines, seed, os.path.join(work, "x"), threads)
                    w.writerow([dname, r, res, mode, filt, COST_SPP, seed, t])
                    f.flush()
                    print(f"  {dname} {mode:12s} {filt:8s} {COST_SPP} spp: {t:.2f} s", flush=True)
    shutil.rmtree(work, ignore_errors=True)


def bound(femto, out_dir, res, ref_spp, runs, threads, coverage_spp=1024):
    """An upper bound on any prefiltering's equal-RMSE speed-up at 1 spp (btf_bound.csv).
    Whatever a material returns, a 1-spp render is black where its camera sample misses the
    sphere; the least error it can then have is an oracle's that returns the pixel's exact value
    wherever the sample hits ("pixel" oracle: the reference's value), which leaves only the
    silhouette's error: that is the bound. A second oracle ("footprint") returns the
    reference's value over the fraction c of the pixel the sphere covers (the surface's mean
    over the covered part, what an exact filter of the surface alone could return): for
    comparison, not a bound (it overshoots where c < 1, and real renders can beat it). Both are
    exact inside the sphere, terminator included. c comes from renders of the sphere as an
    emitter of radiance 1 (COVERAGE_SPP samples), the hits from the same scene at 1 spp with
    the seeds of the BTF renders (the same camera samples), once with ldsampler's jittered
    sample and once with a ray through each pixel's centre (the "-centre" configurations'
    sampler: a bound for each). The equal-error N comes from the multisampled medians of
    btf_runs.csv (run first, at the same RES), and the bound on the speed-up is that N: the
    time of N unfiltered samples over one prefiltered sample of the same cost. Beside them,
    for scale: the unfiltered BTF's own 1-spp error with each sampler (what the ray through
    the centre gains without any prefiltering)."""
    rows = list(csv.DictReader(open(os.path.join(out_dir, "btf_runs.csv"))))
    work = tempfile.mkdtemp()
    btf, cache = btf_file(femto, work)
    out_rows = []
    for i, r in enumerate(RATIOS):
        dname, dist = f"d{i}", camera_distance(r, res)
        ms_runs = {}
        for row in rows:
            if row["distance"] == dname and row["mode"] == "multisampled":
                assert int(row["res"]) == res, "btf_runs.csv was measured at another --res"
                ms_runs.setdefault(int(row["spp"]), []).append(
                    (float(row["rmse"]), float(row["seconds"])))
        ms = {n: tuple(float(np.median([x[k] for x in v])) for k in range(2))
              for n, v in ms_runs.items()}
        xml, xml_centre = scene_files(work, dname, dist, btf, cache)
        mask = os.path.join(work, f"mask-{dname}.xml")
        open(mask, "w").write(mask_xml(dist, btf))
        mask_centre = os.path.join(work, f"mask-{dname}-centre.xml")
        open(mask_centre, "w").write(through_centres(mask_xml(dist, btf)))
        base = {"res": str(res)}
        halves = [render(femto, xml, dict(base, prefilter="false", spp=str(ref_spp // 2)),
                         1000 + h, os.path.join(work, f"ref{h}"), threads)[1] for h in (1, 2)]
        ref = Reference(halves)
        noise = math.sqrt(float(ref.var.mean()))
        _, cover = render(femto, mask, dict(base, spp=str(coverage_spp)), 1,
                          os.path.join(work, "cover"), threads)
        c = cover[..., :1]
        footprint_mean = np.where(c > 0, ref.image / np.maximum(c, 1e-30), 0.0)
        for sampler, scene, btf_scene in (("jittered", mask, xml),
                                          ("centre", mask_centre, xml_centre)):
            # Beside the oracles: the unfiltered BTF at 1 spp with the same sampler.
            errs = {"footprint": [], "pixel": [], "unfiltered": []}
            for seed in range(1, runs + 1):
                _, hit = render(femto, scene, dict(base, spp="1"), seed,
                                os.path.join(work, "hit"), threads)
                h = hit[..., :1]
                for name, value in (("footprint", footprint_mean), ("pixel", ref.image)):
                    errs[name].append(math.sqrt(float(((h * value - ref.image) ** 2).mean())))
                _, img = render(femto, btf_scene, dict(base, prefilter="false", spp="1"), seed,
                                os.path.join(work, "x"), threads)
                errs["unfiltered"].append(ref.errors(img)[0])
            row = [dname, r, res, sampler, ref_spp, f"{noise:.3g}", f"{float(c.mean()):.5g}",
                   f"{int(((c > 0) & (c < 1)).sum())}"]
            for name in ("footprint", "pixel", "unfiltered"):
                e = float(np.median(errs[name]))
                n, _, flag = (equal_error(ms, e) if e > 0 else
                              (math.inf, math.inf, "no silhouette in view: the oracle is exact"))
                row += [f"{e:.6g}", f"{n:.3g}", flag]
                print(f"{dname} (r {r}), {sampler} sample: {name} RMSE {e:.4g} "
                      f"(runs {', '.join('%.4g' % x for x in errs[name])}): equal to N = "
                      f"{n:.3g} unfiltered samples {flag}", flush=True)
            out_rows.append(row)
        print(f"  {dname}: reference noise {noise:.3g}, sphere covers {c.mean():.4f} of the "
              f"image, {row[7]} pixels in part", flush=True)
    with open(os.path.join(out_dir, "btf_bound.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["distance", "r", "res", "sampler", "ref_spp", "ref_noise_rmse",
                    "coverage_mean", "partly_covered_pixels", "rmse_oracle_footprint",
                    "bound_footprint", "note_footprint", "rmse_oracle_pixel", "bound_pixel",
                    "note_pixel", "rmse_unfiltered_1spp", "equal_error_spp_unfiltered_1spp",
                    "note_unfiltered_1spp"])
        w.writerows(out_rows)
    for sampler in ("jittered", "centre"):
        for col, name in ((9, "footprint mean"), (12, "pixel value")):
            v = [float(row[col]) for row in out_rows if row[0] != "d0" and row[3] == sampler]
            print(f"bound on the mean speed-up over d1-d4, {sampler} sample ({name} oracle): "
                  f"{np.mean(v):.3g} (d1..d4: {', '.join('%.3g' % x for x in v)})", flush=True)
    shutil.rmtree(work, ignore_errors=True)


RUN_COLUMNS = ["distance", "r", "camera_distance", "res", "mode", "filter", "scale", "spp",
               "seed", "seconds", "rmse", "rmse_inner", "ssim"]


def summarise(out_dir):
    """btf_speedup.csv and btf.png from btf_runs.csv: per distance, the medians of the
    multisampled runs per N and of the prefiltered runs per (filter, scale), and the
    equal-error speed-ups on the whole image's RMSE and on the inner pixels' RMSE."""
    rows = list(csv.DictReader(open(os.path.join(out_dir, "btf_runs.csv"))))
    data = {}
    for row in rows:
        d = data.setdefault(row["distance"], (int(row["r"]), int(row["res"]), {}, {}))
        key = int(row["spp"]) if row["mode"] == "multisampled" else (row["filter"], row["scale"])
        (d[2] if row["mode"] == "multisampled" else d[3]).setdefault(key, []).append(
            [float(row[k]) for k in ("rmse", "seconds", "rmse_inner", "ssim")])
    med = lambda runs: tuple(float(np.median([x[k] for x in runs])) for k in range(4))
    # Per distance and filter, a prefiltered sample's cost over an unfiltered one's (btf_cost.csv
    # from --cost; medians of its runs), if measured.
    cost_ratio = {}
    cost_file = os.path.join(out_dir, "btf_cost.csv")
    if os.path.exists(cost_file):
        times = {}
        for row in csv.DictReader(open(cost_file)):
            times.setdefault((row["distance"], row["filter"]), []).append(float(row["seconds"]))
        for (dname, filt), v in times.items():
            if filt:
                cost_ratio[(dname, filt)] = float(np.median(v)) / float(
                    np.median(times[(dname, "")]))
    speed_rows, plot_data = [], {}
    for dname in sorted(data):
        r, res, ms_runs, pf_runs = data[dname]
        ms = {n: med(v) for n, v in ms_runs.items()}  # (rmse, seconds, rmse_inner, ssim)
        pf = {k: med(v) for k, v in pf_runs.items()}
        plot_data[dname] = (r, ms, pf, res)
        ms_inner = {n: (v[2], v[1]) for n, v in ms.items()}
        for (filt, scale), (e_pf, t_pf, ei_pf, s_pf) in pf.items():
            n, t_ms, flag = equal_error(ms, e_pf)
            ni, ti_ms, flag_i = equal_error(ms_inner, ei_pf)
            c = cost_ratio.get((dname, filt), float("nan"))
            speed_rows.append([dname, r, res, filt, scale, f"{e_pf:.6g}", f"{ei_pf:.6g}",
                               f"{s_pf:.5f}", f"{t_pf:.3f}", f"{n:.3g}", f"{t_ms:.3f}",
                               f"{t_ms / t_pf:.3g}", flag, f"{ni:.3g}", f"{ti_ms / t_pf:.3g}",
                               flag_i, f"{c:.3g}", f"{n / c:.3g}", f"{ni / c:.3g}"])
            print(f"{dname} {filt:8s} s={scale:3s}: equal RMSE at N = {n:.3g}: t_ms {t_ms:.3f} s"
                  f" / t_pf {t_pf:.3f} s = {t_ms / t_pf:.3g}x {flag}; inner pixels: N = "
                  f"{ni:.3g}, {ti_ms / t_pf:.3g}x {flag_i}", flush=True)
    with open(os.path.join(out_dir, "btf_speedup.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["distance", "r", "res", "filter", "scale", "rmse_pf", "rmse_inner_pf",
                    "ssim_pf", "seconds_pf", "equal_error_spp", "seconds_ms_at_equal_error",
                    "speedup", "note", "equal_error_spp_inner", "speedup_inner", "note_inner",
                    "cost_per_sample_pf_over_ms", "speedup_by_cost", "speedup_inner_by_cost"])
        w.writerows(speed_rows)
    print("mean speed-up over d1-d4, whole image / inner pixels (arithmetic mean, geometric "
          "mean):", flush=True)
    for filt in CONFIGS:
        for scale in SCALES:
            for col, what in ((11, "whole"), (14, "inner"), (17, "whole, by cost"),
                              (18, "inner, by cost")):
                v = [float(row[col]) for row in speed_rows
                     if row[3] == filt and row[4] == scale and row[0] != "d0"]
                v = [x for x in v if math.isfinite(x)]
                if v:
                    print(f"  {filt:8s} s={scale:3s} {what}: {np.mean(v):.3g}, "
                          f"{math.exp(np.mean(np.log(v))):.3g} (d1..d4: "
                          f"{', '.join('%.3g' % x for x in v)})", flush=True)
    plot(plot_data, os.path.join(out_dir, "btf.png"))


def plot(data, path):
    """Error against time per distance: the multisampled medians per N (a line) and the
    prefiltered medians per (filter, scale) (points); top the whole image, bottom the inner
    pixels."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(2, len(data), figsize=(3.2 * len(data) + 2.5, 6.4), squeeze=False)
    markers = {"box": "s", "gaussian": "o", "lanczos": "^"}
    colours = {"0.5": "tab:blue", "1": "tab:orange", "2": "tab:green"}
    for col, (dname, (r, ms, pf, res)) in enumerate(data.items()):
        ns = sorted(ms)
        for row, (k, what) in enumerate(((0, "RMSE, whole image"), (2, "RMSE, inner pixels"))):
            ax = axes[row][col]
            ax.loglog([ms[n][1] for n in ns], [ms[n][k] for n in ns], "k.-", lw=1,
                      label=f"multisampled, N = 1..{ns[-1]}")
            for n in (ns[0], ns[-1]):
                ax.annotate(f"N={n}", (ms[n][1], ms[n][k]), fontsize=6)
            for (filt, scale), v in sorted(pf.items()):
                kernel = filt.partition("-")[0]
                ax.loglog([v[1]], [v[k]], markers[kernel], color=colours[scale],
                          ms=7 if filt.endswith("-centre") else 5,
                          mfc=colours[scale] if kernel != filt else "none",
                          label=f"prefiltered {filt}, s = {scale}")
            ax.set_title(f"{dname}: r = {r} ({res}x{res})", fontsize=9)
            ax.set_xlabel("render time (s)", fontsize=8)
            ax.set_ylabel(what, fontsize=8)
            ax.tick_params(labelsize=7)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="center right", fontsize=5.5)  # beside the panels
    fig.tight_layout(rect=(0, 0, 0.86, 1))
    fig.savefig(path, dpi=100)


if __name__ == "__main__":
    main()
