// time: time-uniform angular sampling (thesis ch. 5.6.3, eq. 5.26-5.27, appendix 5.C.3). At a
// medium vertex the distance r to the next vertex is drawn first; the direction is then chosen
// so that the length r + |x_next - light| of the path to a light, and so its time, is uniform
// over its range. Directions toward the light are favoured, which keeps paths inside the
// film's window. With no finite light point to aim at it samples the phase function.
//
// With r and the target's distance L fixed, s(theta) = |x + r w - target| = sqrt(r^2 + L^2 -
// 2 r L cos theta) (eq. 5.114) runs from |L - r| to L + r; sampling s uniformly on it gives
// cos theta = 1 - u 2 min(r, L) (s + |L - r|) / (2 r L), written without cancellation. The
// solid-angle density is r L / (4 pi s min(r, L)): eq. 5.118 divided by 2 pi sin theta for
// L < r (the thesis' case), and it also covers L > r. (The thesis' inverse cdf, eq. 5.117, is
// misprinted; this inverts eq. 5.114 directly.)
#include <algorithm>
#include <cmath>

#include "femto/plugin.h"
#include "femto/time_sampling.h"

namespace {

using namespace femto;

constexpr double kPi64 = 3.14159265358979323846;

// The usable geometry of a query: r, the target's distance L and direction.
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

class TimeAngular final : public AngularSampler {
public:
    explicit TimeAngular(const Properties&) {}

    Vec3 sample(const AngularQuery& q, Vec2 u) const override {
        const AngularGeometry a = angular_geometry(q);
        if (!a.usable) return q.phase->sample(q.wi, u);
        const double near = std::abs(a.L - a.r), m = std::min(a.r, a.L);
        const double s = near + double(u.x) * 2 * m;
        const double cos_theta =
            std::clamp(1 - double(u.x) * m * (s + near) / (a.r * a.L), -1.0, 1.0);
        const double sin_theta = std::sqrt(std::max(0.0, 1 - cos_theta * cos_theta));
        const double phi = 2 * kPi64 * double(u.y);
        const Frame frame(a.axis);
        return normalize(frame.to_world(Vec3(float(sin_theta * std::cos(phi)),
                                             float(sin_theta * std::sin(phi)), float(cos_theta))));
    }

    double pdf(const AngularQuery& q, const Vec3& wo) const override {
        const AngularGeometry a = angular_geometry(q);
        if (!a.usable) return double(q.phase->eval(q.wi, wo));
        // s^2 = (r - L)^2 + 2 r L (1 - cos theta), with 1 - cos theta = |wo - axis|^2 / 2 so
        // that small angles (where the density peaks when r is close to L) keep their
        // precision.
        const double dx = double(wo.x) - a.axis.x, dy = double(wo.y) - a.axis.y,
                     dz = double(wo.z) - a.axis.z;
        const double one_minus_cos = std::min(0.5 * (dx * dx + dy * dy + dz * dz), 2.0);
        const double s = std::sqrt((a.r - a.L) * (a.r - a.L) + 2 * a.r * a.L * one_minus_cos);
        const double m = std::min(a.r, a.L);
        return a.r * a.L / (4 * kPi64 * std::max(s, 1e-12 * m) * m);
    }
};

}  // namespace

FEMTO_PLUGIN(TimeAngular, femto::PluginKind::Angular, "time",
             "Time-uniform angular sampling at medium vertices, aimed at a light (ch. 5.6.3, "
             "eq. 5.26-5.27)",
             {})
