// The connection and angular time-sampling routines of ch. 5.6.2-5.6.3 (and equiangular
// sampling, their steady reference), shared by the strategy plugins and by later integrators.
// Everything is in double: the inverse cdfs subtract nearly equal lengths.
#include "femto/time_sampling.h"

#include <algorithm>
#include <cmath>

namespace femto {

namespace {

constexpr double kPi64 = 3.14159265358979323846;

struct D3 {
    double x, y, z;
};
D3 to_d3(const Vec3& v) { return {double(v.x), double(v.y), double(v.z)}; }
double dot(const D3& a, const D3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// The segment seen from its target: l = target - origin, b = l . direction (where the target
// projects on the line), d2 = l.l - b^2 its squared distance from the line, and D that
// distance kept a hair above zero (a target on the line makes equiangular's density a delta).
struct SegmentGeometry {
    double l2, b, d2, D;
};
SegmentGeometry geometry(const ConnectionQuery& q) {
    const D3 o = to_d3(q.origin), c = to_d3(q.target), w = to_d3(q.direction);
    const D3 l{c.x - o.x, c.y - o.y, c.z - o.z};
    const double l2 = dot(l, l), b = dot(l, w), d2 = std::max(l2 - b * b, 0.0);
    return {l2, b, d2, std::max(std::sqrt(d2), 1e-9 * (1.0 + std::sqrt(l2)))};
}

// |x(r) - target| for x(r) = origin + r direction, as (r - b)^2 + d2: with the target nearly
// on the line, d2 is tiny and must not be lost against r^2 and l.l.
double distance_to_target(const SegmentGeometry& g, double r) {
    return std::sqrt((r - g.b) * (r - g.b) + g.d2);
}

// The range [t_a, t_b] of the length T(r) = r + |x(r) - target| over a finite segment;
// empty (t_b <= t_a) when the target lies ahead on the line.
struct LengthRange {
    double t_a, t_b;
    bool empty() const { return !(t_b > t_a * (1 + 1e-12)); }
};
LengthRange length_range(const ConnectionQuery& q, const SegmentGeometry& g) {
    return {std::sqrt(g.l2), q.length + distance_to_target(g, q.length)};
}

// The angles, seen from the target's foot on the line, of the segment's start and end (pi / 2
// for an infinite segment); empty when the segment is too short to resolve.
struct AngleRange {
    double theta_a, theta_b;
    bool empty() const { return !(theta_b > theta_a); }
};
AngleRange angle_range(const ConnectionQuery& q, const SegmentGeometry& g) {
    return {std::atan2(-g.b, g.D),
            std::isfinite(q.length) ? std::atan2(q.length - g.b, g.D) : kPi64 / 2};
}

}  // namespace

double ConnectionSampler::equiangular_sample(const ConnectionQuery& q, double u) {
    if (!(q.length > 0)) return -1.0;
    const SegmentGeometry g = geometry(q);
    const AngleRange range = angle_range(q, g);
    if (range.empty()) return -1.0;
    const double r = g.b + g.D * std::tan(range.theta_a + u * (range.theta_b - range.theta_a));
    return std::clamp(r, 0.0, std::nextafter(q.length, 0.0));
}

double ConnectionSampler::equiangular_pdf(const ConnectionQuery& q, double r) {
    if (!(r >= 0 && r < q.length)) return 0.0;
    const SegmentGeometry g = geometry(q);
    const AngleRange range = angle_range(q, g);
    if (range.empty()) return 0.0;
    const double h = r - g.b;
    return g.D / ((range.theta_b - range.theta_a) * (g.D * g.D + h * h));
}

// T(r) = r + s(r) grows from T(0) = |l| to T(length); sampling T uniformly and inverting
// (eq. 5.107 with c = eta = 1; eta only rescales time) gives r = (T^2 - l.l) / (2 (T - b)),
// and the density is T'(r) / (T(length) - T(0)) = (1 + (r - b) / s(r)) / range (eq. 5.109).
double ConnectionSampler::line_to_point_sample(const ConnectionQuery& q, double u) {
    if (!(q.length > 0) || !std::isfinite(q.length)) return -1.0;
    const SegmentGeometry g = geometry(q);
    const LengthRange range = length_range(q, g);
    if (range.empty()) return -1.0;  // target ahead on the line: no time range
    const double t = range.t_a + u * (range.t_b - range.t_a);
    // T^2 - l.l = (T - |l|)(T + |l|) avoids cancelling when T is close to |l|.
    const double r = (t - range.t_a) * (t + range.t_a) / (2 * (t - g.b));
    return std::clamp(r, 0.0, std::nextafter(q.length, 0.0));
}

double ConnectionSampler::line_to_point_pdf(const ConnectionQuery& q, double r) {
    if (!(r >= 0 && r < q.length) || !std::isfinite(q.length)) return 0.0;
    const SegmentGeometry g = geometry(q);
    const LengthRange range = length_range(q, g);
    if (range.empty()) return 0.0;
    // T'(r) = 1 + (r - b) / s; before the target's foot (r < b) the two terms nearly cancel,
    // so it is written there as d2 / (s (s + b - r)).
    const double s = distance_to_target(g, r);
    const double slope =
        r >= g.b ? 1 + (r - g.b) / std::max(s, 1e-300) : g.d2 / std::max(s * (s + g.b - r), 1e-300);
    return slope / (range.t_b - range.t_a);
}

namespace {

// The usable geometry of a time angular query: r, the target's distance L and direction.
struct AngularGeometry {
    bool usable = false;
    double r = 0, L = 0;
    Vec3 axis;
};
AngularGeometry angular_geometry(const AngularQuery& q) {
    AngularGeometry a;
    if (!q.has_target || !(q.distance > 0) || !std::isfinite(q.distance)) return a;
    const Vec3 l = q.target - q.position;
    a.L = double(length(l));
    a.r = q.distance;
    if (!(a.L > 1e-7) || !std::isfinite(a.L)) return a;
    a.axis = l / float(a.L);
    a.usable = true;
    return a;
}

}  // namespace

// With r and L fixed, s(theta) = |x + r w - target| = sqrt(r^2 + L^2 - 2 r L cos theta)
// (eq. 5.114) runs from |L - r| to L + r; sampling s uniformly on it (so the length r + s, and
// the time, is uniform) gives cos theta = 1 - u 2 min(r, L) (s + |L - r|) / (2 r L), written
// without cancellation. The solid-angle density is r L / (4 pi s min(r, L)), which is
// eq. 5.118 divided by 2 pi sin theta for L < r (the thesis' case), and also covers L > r.
Vec3 AngularSampler::time_sample(const AngularQuery& q, Vec2 u) {
    const AngularGeometry a = angular_geometry(q);
    if (!a.usable) return q.phase->sample(q.wi, u);
    const double near = std::abs(a.L - a.r), m = std::min(a.r, a.L);
    const double s = near + double(u.x) * 2 * m;
    const double cos_theta = std::clamp(1 - double(u.x) * m * (s + near) / (a.r * a.L), -1.0, 1.0);
    const double sin_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
    const double phi = 2 * kPi64 * double(u.y);
    const Frame frame(a.axis);
    return normalize(frame.to_world(Vec3(float(sin_theta * std::cos(phi)),
                                         float(sin_theta * std::sin(phi)), float(cos_theta))));
}

double AngularSampler::time_pdf(const AngularQuery& q, const Vec3& wo) {
    const AngularGeometry a = angular_geometry(q);
    if (!a.usable) return double(q.phase->eval(q.wi, wo));
    // s^2 = (r - L)^2 + 2 r L (1 - cos theta), with 1 - cos theta = |wo - axis|^2 / 2 so that
    // small angles (where the density peaks when r is close to L) keep their precision.
    const double dx = double(wo.x) - a.axis.x, dy = double(wo.y) - a.axis.y,
                 dz = double(wo.z) - a.axis.z;
    const double one_minus_cos = std::min(0.5 * (dx * dx + dy * dy + dz * dz), 2.0);
    const double s = std::sqrt((a.r - a.L) * (a.r - a.L) + 2 * a.r * a.L * one_minus_cos);
    const double m = std::min(a.r, a.L);
    return a.r * a.L / (4 * kPi64 * std::max(s, 1e-12 * m) * m);
}

}  // namespace femto
