// line_to_point: time-uniform shadow connections (thesis ch. 5.6.2, eq. 5.24-5.25, appendix
// 5.C.2). On each ray segment through a medium an extra vertex x(r) is placed so that the
// duration of the two-segment connection origin -> x(r) -> light is uniform over the range
// the segment allows: from the straight line (r = 0, eq. 5.110) to the segment's end or the
// film window's end, whichever comes first (eq. 5.111). A segment with no end and no window
// has no finite time range; there the strategy falls back to equiangular sampling.
//
// With c = eta = 1 (eta only rescales time) the length T(r) = r + s(r), s(r) = |x(r) -
// target|, grows from T(0) = |l| to T(length). Sampling T uniformly and inverting (eq. 5.107)
// gives r = (T^2 - |l|^2) / (2 (T - b)), and the density is T'(r) / (T(length) - T(0)) =
// (1 + (r - b) / s(r)) / range (eq. 5.109). Everything is in double: the inverse cdf
// subtracts nearly equal lengths.
#include <algorithm>
#include <cmath>

#include "femto/plugin.h"
#include "femto/time_sampling.h"

namespace {

using namespace femto;

// The range [t_a, t_b] of T(r) over a finite segment; empty when the target lies ahead on
// the line.
struct LengthRange {
    double t_a, t_b;
    bool empty() const { return !(t_b > t_a * (1 + 1e-12)); }
};
LengthRange length_range(const ConnectionQuery& q, const ConnectionGeometry& g) {
    return {std::sqrt(g.l2), q.length + g.distance_to_target(q.length)};
}

double line_to_point_sample(const ConnectionQuery& q, double u) {
    if (!(q.length > 0) || !std::isfinite(q.length)) return -1.0;
    const ConnectionGeometry g(q);
    const LengthRange range = length_range(q, g);
    if (range.empty()) return -1.0;  // target ahead on the line: no time range
    const double t = range.t_a + u * (range.t_b - range.t_a);
    // T^2 - |l|^2 = (T - |l|)(T + |l|) avoids cancelling when T is close to |l|.
    const double r = (t - range.t_a) * (t + range.t_a) / (2 * (t - g.b));
    return std::clamp(r, 0.0, std::nextafter(q.length, 0.0));
}

double line_to_point_pdf(const ConnectionQuery& q, double r) {
    if (!(r >= 0 && r < q.length) || !std::isfinite(q.length)) return 0.0;
    const ConnectionGeometry g(q);
    const LengthRange range = length_range(q, g);
    if (range.empty()) return 0.0;
    // T'(r) = 1 + (r - b) / s; before the target's foot (r < b) the two terms nearly cancel,
    // so it is written there as d2 / (s (s + b - r)).
    const double s = g.distance_to_target(r);
    const double slope =
        r >= g.b ? 1 + (r - g.b) / std::max(s, 1e-300) : g.d2 / std::max(s * (s + g.b - r), 1e-300);
    return slope / (range.t_b - range.t_a);
}

class LineToPoint final : public ConnectionSampler {
public:
    explicit LineToPoint(const Properties&) {}

    double sample(const ConnectionQuery& q, double u) const override {
        return std::isfinite(q.length) ? line_to_point_sample(q, u) : equiangular_sample(q, u);
    }
    double pdf(const ConnectionQuery& q, double r) const override {
        return std::isfinite(q.length) ? line_to_point_pdf(q, r) : equiangular_pdf(q, r);
    }
};

}  // namespace

FEMTO_PLUGIN(LineToPoint, femto::PluginKind::Connection, "line_to_point",
             "Time-uniform shadow connections through an extra medium vertex (ch. 5.6.2, "
             "eq. 5.24-5.25)",
             {})
