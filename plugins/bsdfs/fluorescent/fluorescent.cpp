// fluorescent: a Lambertian surface that absorbs light and re-emits it later, at another
// colour (thesis ch. 5.7, Fig. 5.16: a chlorophyll bunny glowing red ~10 ns after the pulse).
//
// Physics. Light arriving in colour channel c is absorbed with probability absorption[c]; the
// rest is lost (this material has no elastic reflection, so everything it sends out is
// fluorescence). An absorbed photon is re-emitted with probability `efficiency` (the quantum
// yield), into channel c' with probability e[c'], where e is the `emission` colour normalised
// so that its channels sum to 1 (e = emission / (emission.r + emission.g + emission.b)). The
// re-emission is isotropic over the hemisphere (Lambertian, f = 1/pi) and happens after the
// excited state's lifetime: an exponentially distributed delay with mean `lifetime` tau
// (eq. 5.13's scattering delay Delta t_i, in optical path length = time x c, scene units):
// p(dt) = exp(-dt / tau) / tau, sampled as dt = -tau ln(1 - u).
//
// In the light direction the vertex is the rank-1 colour matrix M = efficiency * e a^T
// (a = absorption): L_out = M L_in, so the re-emitted energy summed over channels is
// efficiency * (a . L_in) <= sum(L_in): energy is conserved, with equality when
// efficiency = 1 and absorption = (1, 1, 1). (Channels count photons: the Stokes shift's loss
// of energy per photon is not modelled.) transfer() returns M; the path tracer applies it to
// everything that arrives at this vertex.
//
// Defaults: absorbs blue (0, 0, 1), re-emits green (0, 1, 0), efficiency 1.
#include <cmath>

#include "femto/bsdf.h"
#include "femto/plugin.h"
#include "femto/warp.h"

namespace {

using namespace femto;

class Fluorescent final : public Bsdf {
public:
    explicit Fluorescent(const Properties& props)
        : absorption_(props.get_color("absorption", Color(0.f, 0.f, 1.f))),
          emission_(props.get_color("emission", Color(0.f, 1.f, 0.f))),
          efficiency_(float(props.get_float("efficiency", 1.0))),
          lifetime_(props.get_float("lifetime", 1.0)) {
        for (int c = 0; c < 3; ++c)
            if (!(absorption_[c] >= 0.f && absorption_[c] <= 1.f))
                props.fail("absorption", "every channel of absorption must lie in [0, 1]");
        if (!(emission_.r >= 0.f && emission_.g >= 0.f && emission_.b >= 0.f) ||
            !(emission_.r + emission_.g + emission_.b > 0.f) || !emission_.is_finite())
            props.fail("emission", "emission must be non-negative, finite and not black");
        emission_ = emission_ / (emission_.r + emission_.g + emission_.b);
        if (!(efficiency_ >= 0.f && efficiency_ <= 1.f))
            props.fail("efficiency", "efficiency (quantum yield) must lie in [0, 1]");
        if (!(lifetime_ >= 0.0) || !std::isfinite(lifetime_))
            props.fail("lifetime", "lifetime must be finite and >= 0");
    }

    uint32_t flags() const override { return kBsdfDiffuseReflection; }

    BsdfSample sample(const Hit& /*hit*/, const Vec3& wi, float /*u_lobe*/, Vec2 u) const override {
        BsdfSample s;
        if (wi.z <= 0.f) return s;
        s.wo = warp::square_to_cosine_hemisphere(u);
        s.pdf = warp::cosine_hemisphere_pdf(s.wo);
        if (!(s.pdf > 0.f)) {
            s.pdf = 0.f;
            return s;
        }
        s.eta = 1.f;
        s.sampled_lobe = kBsdfDiffuseReflection;
        s.weight = Color(1.f);  // (cos / pi) / (cos / pi); the colour is in transfer()
        return s;
    }

    Color eval(const Hit& /*hit*/, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return Color(0.f);
        return Color(wo.z * kInvPi);
    }

    float pdf(const Hit& /*hit*/, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return 0.f;
        return warp::cosine_hemisphere_pdf(wo);
    }

    bool has_delay() const override { return lifetime_ > 0.0; }
    double sample_delay(const Hit& /*hit*/, float u) const override {
        return -lifetime_ * std::log1p(-double(u));
    }

    bool has_transfer() const override { return true; }
    ColorMatrix transfer(const Hit& /*hit*/) const override {
        // M = efficiency * e a^T (emission_ is normalised to sum 1 in the constructor).
        ColorMatrix m;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) m.m[i][j] = efficiency_ * emission_[i] * absorption_[j];
        return m;
    }

private:
    Color absorption_, emission_;
    float efficiency_;
    double lifetime_;
};

}  // namespace

FEMTO_PLUGIN(Fluorescent, femto::PluginKind::Bsdf, "fluorescent",
             "Lambertian fluorescence: absorbs light, re-emits it at another colour after an "
             "exponential delay",
             {{"absorption", "color", "(0, 0, 1)",
               "fraction of each incoming channel absorbed (the rest is lost)"},
              {"emission", "color", "(0, 1, 0)",
               "colour of the re-emitted light (normalised to sum 1 over channels)"},
              {"efficiency", "float", "1", "quantum yield: fraction of absorbed light re-emitted"},
              {"lifetime", "float", "1",
               "mean delay before re-emission (optical path length, scene units)"}})
