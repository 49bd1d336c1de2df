// hg: the Henyey-Greenstein phase function (Mitsuba's `hg`), with asymmetry g in (-1, 1):
//
//     p(wi -> wo) = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^(3/2)),   cos = dot(-wi, wo),
//
// where wi points back toward the previous vertex (femto/medium.h), so g > 0 favours forward
// scattering (wo = -wi), g < 0 backward scattering, and g = 0 is isotropic. The mean cosine
// E[dot(-wi, wo)] is g.
//
// sample() inverts the CDF of cos exactly. The textbook inverse,
//     cos = (1 + g^2 - ((1 - g^2) / (1 - g + 2 g u))^2) / (2 g),
// divides by g and cancels catastrophically for small |g| (it is 0 / 0 at g = 0). With
// t = 2 u - 1 it rearranges, without approximation, to
//     cos = (t + g (2 + t^2 - g^2) / 2) / (1 + g t)^2 + g / 2,
// which has no division by g and is exactly cos = t (the isotropic inverse CDF) at g = 0, so no
// isotropic special case is needed: eval() and sample() stay consistent for every g. Both are
// computed in double precision; the cosine is clamped to [-1, 1] against rounding.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "femto/medium.h"
#include "femto/plugin.h"

namespace {

constexpr double kInv4Pi = 0.07957747154594766788;  // 1 / (4 pi)
constexpr double kTwoPi = 6.28318530717958647692;

class HenyeyGreenstein final : public femto::PhaseFunction {
public:
    explicit HenyeyGreenstein(const femto::Properties& props) {
        g_ = props.get_float("g", 0.0);
        if (!(std::abs(g_) < 1.0)) {
            std::ostringstream os;
            os << "g (the mean cosine of the scattering angle) must lie in (-1, 1), not " << g_;
            props.fail("g", os.str());
        }
    }

    float eval(const femto::Vec3& wi, const femto::Vec3& wo) const override {
        // Isotropic: the same value without the square root (a bidirectional integrator
        // evaluates the phase function several times per connection).
        if (g_ == 0.0) return static_cast<float>(kInv4Pi);
        double c = -(double(wi.x) * wo.x + double(wi.y) * wo.y + double(wi.z) * wo.z);
        c = std::clamp(c, -1.0, 1.0);
        const double denom = 1.0 + g_ * g_ - 2.0 * g_ * c;  // >= (1 - |g|)^2 > 0
        return static_cast<float>(kInv4Pi * (1.0 - g_ * g_) / (denom * std::sqrt(denom)));
    }

    femto::Vec3 sample(const femto::Vec3& wi, femto::Vec2 u) const override {
        const double t = 2.0 * double(u.x) - 1.0;
        const double a = 1.0 + g_ * t;  // >= 1 - |g| > 0
        double c = (t + 0.5 * g_ * (2.0 + t * t - g_ * g_)) / (a * a) + 0.5 * g_;
        c = std::clamp(c, -1.0, 1.0);
        const double s = std::sqrt(std::max(0.0, 1.0 - c * c));
        const double phi = kTwoPi * double(u.y);
        const femto::Frame frame(-wi);
        const femto::Vec3 local(static_cast<float>(s * std::cos(phi)),
                                static_cast<float>(s * std::sin(phi)), static_cast<float>(c));
        return femto::normalize(frame.to_world(local));
    }

private:
    double g_ = 0.0;
};

}  // namespace

FEMTO_PLUGIN(HenyeyGreenstein, femto::PluginKind::Phase, "hg",
             "Henyey-Greenstein phase function; g > 0 scatters forward",
             {{"g", "float", "0",
               "asymmetry, the mean cosine of the scattering angle, in (-1, 1); 0 is isotropic"}})
