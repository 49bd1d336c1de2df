"""Equal-error ratios shared by the media benchmarks' plotting scripts (plot_media.py,
plot_media_bdpt.py)."""
import math


def equal_error_spp(steady, err):
    """spp at which the steady curve reaches `err`: log-log interpolation between its medians,
    extrapolation along slope -1 beyond them (flagged). Non-positive errors are skipped."""
    pts = [(n, e, w) for n, e, w in steady if e > 0]
    if not pts or err <= 0:
        return float("nan"), float("nan"), "none"
    for (n0, e0, w0), (n1, e1, w1) in zip(pts, pts[1:]):
        if (e0 - err) * (e1 - err) <= 0 and e0 != e1:
            f = (math.log(err) - math.log(e0)) / (math.log(e1) - math.log(e0))
            n = math.exp(math.log(n0) + f * (math.log(n1) - math.log(n0)))
            w = math.exp(math.log(w0) + f * (math.log(w1) - math.log(w0)))
            return n, w, "interpolated"
    n_last, e_last, w_last = pts[-1] if err < pts[-1][1] else pts[0]
    n = n_last * e_last / err  # error ~ 1 / n
    return n, w_last * n / n_last, "extrapolated"
