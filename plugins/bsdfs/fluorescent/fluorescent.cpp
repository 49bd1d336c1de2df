// fluorescent: a Lambertian surface that reflects part of the light at once (elastic lobe) and
// absorbs part of it to re-emit it later at another colour (fluorescent lobe): thesis ch. 5.7,
// Fig. 5.16, a chlorophyll bunny that reflects green-ish light as the pulse passes and glows
// red ~10 ns later.
//
// Physics. Light arriving in colour channel c is reflected elastically with probability
// reflectance[c], absorbed with probability absorption[c], and otherwise lost (so
// reflectance[c] + absorption[c] <= 1). Elastic reflection is Lambertian (f = reflectance / pi)
// and takes no time. An absorbed photon is re-emitted with probability `efficiency` (the
// quantum yield), into channel c' with probability e[c'], where e is the `emission` colour
// normalised so that its channels sum to 1 (e = emission / (emission.r + emission.g +
// emission.b)). The re-emission is isotropic over the hemisphere (Lambertian, f = 1/pi) and
// happens after the excited state's lifetime: an exponentially distributed delay with mean
// `lifetime` tau (eq. 5.13's scattering delay Delta t_i, in optical path length = time x c,
// scene units): p(dt) = exp(-dt / tau) / tau.
//
// In the light direction the vertex is the colour matrix diag(r) + M (r = reflectance), the
// elastic part undelayed and the fluorescent part M = efficiency * e a^T (a = absorption,
// rank 1) delayed: L_out = (diag(r) + M) L_in. Summed over channels the output is
// r . L_in + efficiency * (a . L_in) <= sum(L_in): energy is conserved, with equality when
// reflectance + absorption = 1 in every channel and efficiency = 1. (Channels count photons:
// the Stokes shift's loss of energy per photon is not modelled.) Seen white, the surface's
// steady colour is r + efficiency * (a.r + a.g + a.b) e, the reflected colour shifted toward
// the emission's hue (Fig. 5.16a).
//
// Sampling. eval()/sample() are the white Lambertian lobe shared by both parts; the colour and
// the delay are in the vertex event (Bsdf::sample_vertex_event), which picks one part per
// vertex with probability proportional to its energy for white light:
// p_elastic = sum(r) / (sum(r) + efficiency * sum(a)). Elastic: no delay, transfer
// diag(r) / p_elastic. Fluorescent: the same uniform, rescaled to [0, 1) past p_elastic,
// samples dt = -tau ln(1 - u'), transfer M / (1 - p_elastic). When the fluorescent part has no
// energy (absorption or efficiency 0) there is no event and the material is exactly `diffuse`
// with `reflectance` (same results, same random numbers); with reflectance 0 (the default)
// every vertex fluoresces, as a purely fluorescent material.
//
// Defaults: reflects nothing, absorbs blue (0, 0, 1), re-emits green (0, 1, 0), efficiency 1.
#include <cmath>
#include <sstream>

#include "femto/bsdf.h"
#include "femto/plugin.h"
#include "femto/warp.h"

namespace {

using namespace femto;

double channel_sum(const Color& c) { return double(c.r) + double(c.g) + double(c.b); }

class Fluorescent final : public Bsdf {
public:
    explicit Fluorescent(const Properties& props)
        : reflectance_(props.get_color("reflectance", Color(0.f))),
          absorption_(props.get_color("absorption", Color(0.f, 0.f, 1.f))),
          emission_(props.get_color("emission", Color(0.f, 1.f, 0.f))),
          efficiency_(float(props.get_float("efficiency", 1.0))),
          lifetime_(props.get_float("lifetime", 1.0)) {
        for (int c = 0; c < 3; ++c)
            if (!(reflectance_[c] >= 0.f && reflectance_[c] <= 1.f))
                props.fail("reflectance", "every channel of reflectance must lie in [0, 1]");
        for (int c = 0; c < 3; ++c)
            if (!(absorption_[c] >= 0.f && absorption_[c] <= 1.f))
                props.fail("absorption", "every channel of absorption must lie in [0, 1]");
        // Energy conservation per channel; the slack absorbs float rounding of the inputs
        // (0.4 + 0.6 is 1 + 3e-8 in double from float operands).
        for (int c = 0; c < 3; ++c)
            if (double(reflectance_[c]) + double(absorption_[c]) > 1.0 + 1e-6) {
                std::ostringstream msg;
                msg << "reflectance + absorption must not exceed 1 in any channel (energy "
                       "conservation: light is reflected, absorbed or lost), but channel "
                    << "rgb"[c] << " has reflectance " << reflectance_[c] << " + absorption "
                    << absorption_[c] << " = " << reflectance_[c] + absorption_[c];
                props.fail("reflectance", msg.str());
            }
        if (!(emission_.r >= 0.f && emission_.g >= 0.f && emission_.b >= 0.f) ||
            !(emission_.r + emission_.g + emission_.b > 0.f) || !emission_.is_finite())
            props.fail("emission", "emission must be non-negative, finite and not black");
        emission_ = emission_ / (emission_.r + emission_.g + emission_.b);
        if (!(efficiency_ >= 0.f && efficiency_ <= 1.f))
            props.fail("efficiency", "efficiency (quantum yield) must lie in [0, 1]");
        if (!(lifetime_ >= 0.0) || !std::isfinite(lifetime_))
            props.fail("lifetime", "lifetime must be finite and >= 0");

        // Energies of the two parts for white light; pick each in proportion.
        const double elastic = channel_sum(reflectance_);
        const double fluorescent = double(efficiency_) * channel_sum(absorption_);
        has_event_ = fluorescent > 0.0;
        if (!has_event_) {  // nothing fluoresces: exactly `diffuse` with the reflectance
            lobe_colour_ = reflectance_;
            return;
        }
        lobe_colour_ = Color(1.f);
        p_elastic_ = elastic / (elastic + fluorescent);
        const double p_fluorescent = fluorescent / (elastic + fluorescent);  // > 0
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                // diag(r) / p_elastic (never chosen, and left zero, when p_elastic = 0).
                elastic_.m[i][j] =
                    i == j && p_elastic_ > 0.0 ? float(reflectance_[i] / p_elastic_) : 0.f;
                // M / p_fluorescent, M = efficiency * e a^T (emission_ normalised above).
                fluorescent_.m[i][j] =
                    float(double(efficiency_ * emission_[i] * absorption_[j]) / p_fluorescent);
            }
    }

    uint32_t flags() const override { return kBsdfDiffuseReflection; }

    BsdfSample sample(const Hit& /*hit*/, const Vec3& wi, float /*u_lobe*/, Vec2 u) const override {
        return sample_lambertian(wi, u, lobe_colour_);
    }

    Color eval(const Hit& /*hit*/, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return Color(0.f);
        return lobe_colour_ * (wo.z * kInvPi);
    }

    float pdf(const Hit& /*hit*/, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return 0.f;
        return warp::cosine_hemisphere_pdf(wo);
    }

    bool has_vertex_event() const override { return has_event_; }

    VertexEvent sample_vertex_event(const Hit& /*hit*/, float u) const override {
        VertexEvent ev;
        ev.transfers = true;
        if (double(u) < p_elastic_) {  // elastic: at once, diag(r) / p_elastic
            ev.transfer = elastic_;
            return ev;
        }
        // Fluorescent: u' = (u - p) / (1 - p) is uniform on [0, 1) again (and is u itself when
        // p = 0); u < 1 keeps u' <= 1 - 2^-24, so the delay is finite.
        const double v = (double(u) - p_elastic_) / (1.0 - p_elastic_);
        ev.delay = lifetime_ > 0.0 ? -lifetime_ * std::log1p(-v) : 0.0;
        ev.transfer = fluorescent_;
        return ev;
    }

private:
    Color reflectance_, absorption_, emission_;
    float efficiency_;
    double lifetime_;
    bool has_event_ = false;
    Color lobe_colour_;       // colour of eval()/sample(): reflectance without event, else white
    double p_elastic_ = 0.0;  // probability of the elastic event
    ColorMatrix elastic_, fluorescent_;  // event transfers, each over its probability
};

}  // namespace

FEMTO_PLUGIN(Fluorescent, femto::PluginKind::Bsdf, "fluorescent",
             "Lambertian fluorescence: reflects part of the light at once and absorbs part to "
             "re-emit it at another colour after an exponential delay",
             {{"reflectance", "color", "0",
               "fraction of each incoming channel reflected elastically (Lambertian, no delay); "
               "reflectance + absorption <= 1 per channel"},
              {"absorption", "color", "(0, 0, 1)",
               "fraction of each incoming channel absorbed for re-emission (what is neither "
               "reflected nor absorbed is lost)"},
              {"emission", "color", "(0, 1, 0)",
               "colour of the re-emitted light (normalised to sum 1 over channels)"},
              {"efficiency", "float", "1", "quantum yield: fraction of absorbed light re-emitted"},
              {"lifetime", "float", "1",
               "mean delay before re-emission (optical path length, scene units)"}})
