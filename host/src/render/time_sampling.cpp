// Equiangular sampling, the steady reference of the connection strategies of ch. 5.6.2, and
// the segment geometry the connection strategies share. The time strategies' own math lives
// in their plugins (plugins/samplers/). Everything is in double: the inverse cdfs subtract
// nearly equal lengths.
#include "femto/time_sampling.h"

#include <algorithm>
#include <cmath>

namespace femto {

namespace {

constexpr double kPi64 = 3.14159265358979323846;

// The angles, seen from the target's foot on the line, of the segment's start and end (pi / 2
// for an infinite segment); empty when the segment is too short to resolve.
struct AngleRange {
    double theta_a, theta_b;
    bool empty() const { return !(theta_b > theta_a); }
};
AngleRange angle_range(const ConnectionQuery& q, const ConnectionGeometry& g) {
    return {std::atan2(-g.b, g.D),
            std::isfinite(q.length) ? std::atan2(q.length - g.b, g.D) : kPi64 / 2};
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
    const AngleRange range = angle_range(q, g);
    if (range.empty()) return -1.0;
    const double r = g.b + g.D * std::tan(range.theta_a + u * (range.theta_b - range.theta_a));
    return std::clamp(r, 0.0, std::nextafter(q.length, 0.0));
}

double equiangular_pdf(const ConnectionQuery& q, double r) {
    if (!(r >= 0 && r < q.length)) return 0.0;
    const ConnectionGeometry g(q);
    const AngleRange range = angle_range(q, g);
    if (range.empty()) return 0.0;
    const double h = r - g.b;
    return g.D / ((range.theta_b - range.theta_a) * (g.D * g.D + h * h));
}

}  // namespace femto
