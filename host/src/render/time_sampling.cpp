// Equiangular sampling, the steady reference of the connection strategies of ch. 5.6.2, and
// the segment geometry the connection strategies share. The time strategies' own math lives
// in their plugins (plugins/samplers/). Everything is in double: the inverse cdfs subtract
// nearly equal lengths.
#include "femto/time_sampling.h"

#include <algorithm>
#include <cmath>

namespace femto {

namespace {

// The angle the segment spans seen from the target's foot on the line (theta_b - theta_a, the
// angles of its end and start; not positive when the segment is too short to resolve). One atan2:
// atan(x) - atan(y) = atan2(x - y, 1 + x y) with x = (length - b) / D and y = -b / D, scaled by
// D^2 (for an infinite segment pi / 2 - atan(y) = atan2(1, y)). Two angles cost twice as much
// (the density's only transcendental, which connection strategies evaluate in every MIS
// weight) and cancel on short segments.
double angle_span(const ConnectionQuery& q, const ConnectionGeometry& g) {
    return std::isfinite(q.length) ? std::atan2(q.length * g.D, g.D * g.D - g.b * (q.length - g.b))
                                   : std::atan2(g.D, -g.b);
}

}  // namespace

ConnectionGeometry::ConnectionGeometry(const ConnectionQuery& q) {
    const double lx = double(q.target.x) - q.origin.x, ly = double(q.target.y) - q.origin.y,
                 lz = double(q.target.z) - q.origin.z;
    l2 = lx * lx + ly * ly + lz * lz;
    b = lx * q.direction.x + ly * q.direction.y + lz * q.direction.z;
    d2 = std::max(l2 - b * b, 0.0);
    // A target on the line would make equiangular's density a delta.
    D = std::max(std::sqrt(d2), 1e-9 * (1.0 + std::sqrt(l2)));
}

double equiangular_sample(const ConnectionQuery& q, double u) {
    if (!(q.length > 0)) return -1.0;
    const ConnectionGeometry g(q);
    const double span = angle_span(q, g);
    if (!(span > 0)) return -1.0;
    const double r = g.b + g.D * std::tan(std::atan2(-g.b, g.D) + u * span);
    return std::clamp(r, 0.0, std::nextafter(q.length, 0.0));
}

double equiangular_pdf(const ConnectionQuery& q, double r) {
    if (!(r >= 0 && r < q.length)) return 0.0;
    const ConnectionGeometry g(q);
    const double span = angle_span(q, g);
    if (!(span > 0)) return 0.0;
    const double h = r - g.b;
    return g.D / (span * (g.D * g.D + h * h));
}

}  // namespace femto
