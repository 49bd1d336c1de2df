// Synthetic V-groove BTF (btf/vgroove.h): exact texel averages by 2D ray casting against the
// profile, and the independent closed form of the period average.
#include "btf/vgroove.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace femto::btf {

namespace {

constexpr double kHalfPi = 1.57079632679489661923;

struct Dir3 {
    double x, y, z;
};
Dir3 to_double(const Vec3& w) { return {w.x, w.y, w.z}; }
double inner(const Dir3& a, const Dir3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

/// A point or direction in the xz-plane (the cross-section of the grooves).
struct Point2 {
    double x, z;
};
double cross2(Point2 a, Point2 b) { return a.x * b.z - a.z * b.x; }

void check_groove(const VGroove& g) {
    if (!(g.slope_angle > 0 && g.slope_angle < kHalfPi))
        throw std::invalid_argument("vgroove: slope_angle must be in (0, pi/2)");
}

Dir3 facet_normal(const VGroove& g, Facet f) {
    const double s = std::sin(g.slope_angle), c = std::cos(g.slope_angle);
    return {f == Facet::Left ? s : -s, 0.0, c};
}

double facet_length(const VGroove& g) { return 0.5 / std::cos(g.slope_angle); }

/// Reflectance factor of a lit point of a facet with normal n.
double lit_reflectance(const VGroove& g, const Dir3& n, const Dir3& l) {
    return g.albedo * std::max(0.0, inner(n, l)) / l.z;
}

// ---- Ray casting -------------------------------------------------------------------------

struct FacetSegment {
    Point2 a, b;  // endpoints
    Facet facet;
};

/// The facets of periods [period - 1, period + 1]: a ray starting inside period's groove
/// leaves it before it could reach farther periods (the groove is convex).
std::array<FacetSegment, 6> facets_around(const VGroove& g, double period) {
    const double depth = std::tan(g.slope_angle) / 2;
    std::array<FacetSegment, 6> out{};
    for (int k = 0; k < 3; ++k) {
        const double x = period - 1 + k;
        out[2 * k] = {{x, 0}, {x + 0.5, -depth}, Facet::Left};
        out[2 * k + 1] = {{x + 0.5, -depth}, {x + 1, 0}, Facet::Right};
    }
    return out;
}

/// Ray parameter t of o + t d on the segment, or +inf if it misses or t < t_min.
double intersect(Point2 o, Point2 d, const FacetSegment& s, double t_min) {
    const Point2 e{s.b.x - s.a.x, s.b.z - s.a.z};
    const double denom = cross2(d, e);
    const double inf = std::numeric_limits<double>::infinity();
    if (denom == 0) return inf;  // parallel: grazing, no area to hit
    const Point2 ao{s.a.x - o.x, s.a.z - o.z};
    const double t = cross2(ao, e) / denom, along = cross2(ao, d) / denom;
    return (along >= 0 && along <= 1 && t >= t_min) ? t : inf;
}

struct RayHit {
    double t;
    int index;  // into the segment array, -1 if none
};

RayHit first_hit(Point2 o, Point2 d, const std::array<FacetSegment, 6>& segments, double t_min,
                 int skip_index) {
    RayHit best{std::numeric_limits<double>::infinity(), -1};
    for (int i = 0; i < 6; ++i) {
        if (i == skip_index) continue;
        const double t = intersect(o, d, segments[static_cast<size_t>(i)], t_min);
        if (t < best.t) best = {t, i};
    }
    return best;
}

/// Shadow rays start on a facet; hits closer than this are the shared vertex, not a blocker.
constexpr double kShadowTMin = 1e-12;

double reflectance_by_ray_casting(const VGroove& g, double x, const Dir3& l, const Dir3& v) {
    const auto segments = facets_around(g, std::floor(x));
    const RayHit view = first_hit({x, 0}, {-v.x, -v.z}, segments, 0.0, -1);
    if (view.index < 0) return 0;  // only at a degenerate rim point
    const FacetSegment& facet = segments[static_cast<size_t>(view.index)];
    const Dir3 n = facet_normal(g, facet.facet);
    if (inner(n, l) <= 0) return 0;  // faces away from the light
    const Point2 p{x - view.t * v.x, -view.t * v.z};
    const RayHit shadow = first_hit(p, {l.x, l.z}, segments, kShadowTMin, view.index);
    return shadow.index < 0 ? lit_reflectance(g, n, l) : 0.0;
}

/// B over one period: constant on [breaks[k], breaks[k+1]) with value values[k].
struct PeriodProfile {
    std::vector<double> breaks;
    std::vector<double> values;
    double period_integral = 0;
};

double fractional(double x) { return x - std::floor(x); }

/// Where B may jump in [0, 1): the rim and the bottom vertex projected along v, and the
/// shadow edge that the rim casts along l, projected along v. A superset is harmless. The
/// rims at x = 0 and x = 1 coincide modulo the period, so one shadow ray covers both.
std::vector<double> candidate_breaks(const VGroove& g, const Dir3& l, const Dir3& v) {
    const double depth = std::tan(g.slope_angle) / 2;
    const double v_slope = v.x / v.z;  // projection along v: x_plane = x - z v.x / v.z
    std::vector<double> breaks{0.0, 1.0, fractional(0.5 + depth * v_slope)};
    const auto segments = facets_around(g, 0.0);
    const RayHit edge = first_hit({0, 0}, {-l.x, -l.z}, segments, kShadowTMin, -1);
    if (edge.index >= 0) {
        const Point2 p{-edge.t * l.x, -edge.t * l.z};
        breaks.push_back(fractional(p.x - p.z * v_slope));
    }
    std::sort(breaks.begin(), breaks.end());
    breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());
    return breaks;
}

PeriodProfile build_profile(const VGroove& g, const Vec3& l_in, const Vec3& v_in) {
    check_groove(g);
    if (!(v_in.z > 0)) throw std::invalid_argument("vgroove: the view direction needs v.z > 0");
    const Dir3 l = to_double(l_in), v = to_double(v_in);
    PeriodProfile profile;
    if (!(l.z > 0)) {  // no direct light: B = 0 everywhere
        profile.breaks = {0.0, 1.0};
        profile.values = {0.0};
        return profile;
    }
    profile.breaks = candidate_breaks(g, l, v);
    for (size_t k = 0; k + 1 < profile.breaks.size(); ++k) {
        const double lo = profile.breaks[k], hi = profile.breaks[k + 1];
        const double value = reflectance_by_ray_casting(g, 0.5 * (lo + hi), l, v);
        profile.values.push_back(value);
        profile.period_integral += value * (hi - lo);
    }
    return profile;
}

/// Integral of B over [f0, f1] within one period (0 <= f0 <= f1 <= 1).
double integrate_within_period(const PeriodProfile& profile, double f0, double f1) {
    double sum = 0;
    for (size_t k = 0; k < profile.values.size(); ++k) {
        const double lo = std::max(f0, profile.breaks[k]);
        const double hi = std::min(f1, profile.breaks[k + 1]);
        if (hi > lo) sum += profile.values[k] * (hi - lo);
    }
    return sum;
}

}  // namespace

// ---- Public API ---------------------------------------------------------------------------

double vgroove_average(const VGroove& g, double x0, double x1, const Vec3& l, const Vec3& v) {
    if (x0 == x1) return vgroove_reflectance_at(g, x0, l, v);
    if (x1 < x0) std::swap(x0, x1);
    const PeriodProfile profile = build_profile(g, l, v);
    const double p0 = std::floor(x0), p1 = std::floor(x1);
    const double f0 = x0 - p0, f1 = x1 - p1;
    double integral;
    if (p0 == p1) {  // within one period: no cancellation for short intervals
        integral = integrate_within_period(profile, f0, f1);
    } else {
        integral = integrate_within_period(profile, f0, 1.0) +
                   (p1 - p0 - 1) * profile.period_integral +
                   integrate_within_period(profile, 0.0, f1);
    }
    return integral / (x1 - x0);
}

std::vector<double> vgroove_texels(const VGroove& g, int W, const Vec3& l, const Vec3& v) {
    if (W < 1) throw std::invalid_argument("vgroove: W must be >= 1");
    const PeriodProfile profile = build_profile(g, l, v);
    std::vector<double> texels(static_cast<size_t>(W));
    for (int i = 0; i < W; ++i) {
        const double lo = static_cast<double>(i) / W, hi = static_cast<double>(i + 1) / W;
        texels[static_cast<size_t>(i)] = integrate_within_period(profile, lo, hi) * W;
    }
    return texels;
}

double vgroove_reflectance_at(const VGroove& g, double x, const Vec3& l, const Vec3& v) {
    check_groove(g);
    if (!(v.z > 0)) throw std::invalid_argument("vgroove: the view direction needs v.z > 0");
    if (!(l.z > 0)) return 0;
    return reflectance_by_ray_casting(g, x, to_double(l), to_double(v));
}

double vgroove_visible_fraction(const VGroove& g, Facet f, const Vec3& w_in) {
    check_groove(g);
    const Dir3 n = facet_normal(g, f), w = to_double(w_in);
    const double facing = inner(n, w);
    if (facing <= 0) return 0;  // back-facing (or exactly grazing): no visible area
    return std::clamp(2 * n.z * w.z / facing, 0.0, 1.0);
}

double vgroove_projected_width(const VGroove& g, Facet f, const Vec3& w) {
    if (!(w.z > 0)) return 0;
    const double facing = std::max(0.0, inner(facet_normal(g, f), to_double(w)));
    return vgroove_visible_fraction(g, f, w) * facet_length(g) * facing / w.z;
}

double vgroove_period_average(const VGroove& g, const Vec3& l_in, const Vec3& v_in) {
    check_groove(g);
    if (!(v_in.z > 0)) throw std::invalid_argument("vgroove: the view direction needs v.z > 0");
    if (!(l_in.z > 0)) return 0;
    const Dir3 l = to_double(l_in), v = to_double(v_in);
    double sum = 0;
    for (Facet f : {Facet::Left, Facet::Right}) {
        const Dir3 n = facet_normal(g, f);
        const double lit_and_visible =
            std::min(vgroove_visible_fraction(g, f, v_in), vgroove_visible_fraction(g, f, l_in));
        sum += std::max(0.0, inner(n, l)) * lit_and_visible * facet_length(g) *
               std::max(0.0, inner(n, v)) / v.z;
    }
    return g.albedo * sum / l.z;
}

}  // namespace femto::btf
