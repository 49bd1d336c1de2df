// thindielectric: a thin dielectric slab such as a window pane (Mitsuba 3's `thindielectric`).
//
// The slab's two parallel faces are collapsed into one surface. Light is either reflected into
// the mirror direction with the slab's total reflectance, summed over its internal bounces,
//   R' = R + T^2 R / (1 - R^2) = 2 R / (1 + R),   T = 1 - R,
// R the Fresnel reflectance of one face at the incidence angle, or passes straight through
// (wo = -wi) with T' = 1 - R': the refractions into and out of parallel faces cancel, and the
// sideways offset inside a thin slab is neglected. sample() picks reflection with probability
// R', so the weights are the specular_reflectance / specular_transmittance factors alone. Both
// sides behave alike.
//
// The path's refractive index does not change: a transmission reports eta = 1, so
// femto::MediumTracker::refract() keeps the index the path had (the light leaves the slab into
// the medium it came from). Time: the slab is thin, so crossing it adds no optical length, and
// neither do the internal bounces summed in R' (each adds 2 eta d / cos_t, zero for zero
// thickness): a thin pane neither delays nor displaces light. A pane whose thickness matters in
// time is a `dielectric` box.
#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include "femto/bsdf.h"
#include "femto/fresnel.h"
#include "femto/plugin.h"
#include "femto/texture.h"

namespace {

using namespace femto;

class ThinDielectric final : public Bsdf {
public:
    explicit ThinDielectric(const Properties& props)
        : specular_reflectance_(get_texture(props, "specular_reflectance", Color(1.f))),
          specular_transmittance_(get_texture(props, "specular_transmittance", Color(1.f))) {
        const float int_ior = read_ior(props, "int_ior", "bk7");
        const float ext_ior = read_ior(props, "ext_ior", "air");
        eta_ = int_ior / ext_ior;
    }

    uint32_t flags() const override { return kBsdfDeltaReflection | kBsdfDeltaTransmission; }

    BsdfSample sample(const Hit& hit, const Vec3& wi, float u_lobe, Vec2) const override {
        BsdfSample s;
        if (wi.z == 0.f) return s;  // grazing: no side to scatter from
        const float r = fresnel_dielectric(std::abs(wi.z), eta_).r;
        const float r_slab = 2.f * r / (1.f + r);
        s.eta = 1.f;  // the index is the same on both sides of the slab
        if (u_lobe < r_slab) {
            s.wo = Vec3(-wi.x, -wi.y, wi.z);
            s.pdf = r_slab;
            s.sampled_lobe = kBsdfDeltaReflection;
            s.weight = specular_reflectance_->eval(hit);
        } else {
            s.wo = -wi;
            s.pdf = 1.f - r_slab;
            s.sampled_lobe = kBsdfDeltaTransmission;
            s.weight = specular_transmittance_->eval(hit);
        }
        return s;
    }

    Color eval(const Hit&, const Vec3&, const Vec3&) const override { return Color(0.f); }
    float pdf(const Hit&, const Vec3&, const Vec3&) const override { return 0.f; }

private:
    float eta_ = 1.f;  ///< int_ior / ext_ior
    std::shared_ptr<Texture> specular_reflectance_, specular_transmittance_;
};

}  // namespace

FEMTO_PLUGIN(
    ThinDielectric, femto::PluginKind::Bsdf, "thindielectric",
    "Thin dielectric slab (window pane): Fresnel reflection summed over its internal "
    "bounces, straight transmission without delay",
    {{"int_ior", "float|string", "bk7",
      "index of refraction of the slab (number or name: water, bk7, ...)"},
     {"ext_ior", "float|string", "air", "exterior index of refraction (number or name)"},
     {"specular_reflectance", "color|texture", "1", "factor on the reflection (physically 1)"},
     {"specular_transmittance", "color|texture", "1", "factor on the transmission (physically 1)"}})
