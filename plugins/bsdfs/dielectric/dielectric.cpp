// dielectric: a smooth interface between two dielectrics, e.g. glass in air (Mitsuba's
// `dielectric`).
//
// Reflection and refraction are both delta lobes. sample() picks reflection with probability
// R (the unpolarised Fresnel reflectance) and refraction with probability 1 - R, so the weight
// of either is the specular_reflectance / specular_transmittance factor alone; under total
// internal reflection R = 1. sample.eta reports n_t / n_i of the crossing (1 for reflection).
// Both sides scatter: wi.z < 0 means the path arrives from inside (int_ior).
//
// Radiance convention: femto traces paths from the camera and carries importance-weighted
// radiance; the 1 / eta^2 factor by which radiance changes when it crosses an interface
// (the non-symmetric part of the refraction BSDF) is deliberately NOT applied. It cancels on
// any path that leaves the medium it entered, which is every path from a camera in air to an
// emitter in air; it would only matter for sensors or emitters inside a dielectric. This
// keeps refraction energy-conserving in the white-furnace sense (R + T = 1). (Mitsuba
// multiplies the refracted weight by eta_ti^2 in Radiance mode.)
#include <memory>
#include <optional>
#include <string>

#include "femto/bsdf.h"
#include "femto/fresnel.h"
#include "femto/plugin.h"
#include "femto/texture.h"

namespace {

using namespace femto;

class Dielectric final : public Bsdf {
public:
    explicit Dielectric(const Properties& props)
        : specular_reflectance_(get_texture(props, "specular_reflectance", Color(1.f))),
          specular_transmittance_(get_texture(props, "specular_transmittance", Color(1.f))) {
        const float int_ior = read_ior(props, "int_ior", "bk7");
        const float ext_ior = read_ior(props, "ext_ior", "air");
        eta_ = int_ior / ext_ior;
    }

    uint32_t flags() const override { return kBsdfDeltaReflection | kBsdfDeltaTransmission; }

    BsdfSample sample(const Hit& hit, const Vec3& wi, float u_lobe, Vec2) const override {
        BsdfSample s;
        const FresnelDielectric f = fresnel_dielectric(wi.z, eta_);
        if (u_lobe < f.r) {
            s.wo = Vec3(-wi.x, -wi.y, wi.z);
            s.pdf = f.r;
            s.eta = 1.f;
            s.sampled_lobe = kBsdfDeltaReflection;
            s.weight = specular_reflectance_->eval(hit);
        } else {
            // Snell: the tangential part scales by eta_ti and flips, the normal part is cos_t.
            s.wo = Vec3(-wi.x * f.eta_ti, -wi.y * f.eta_ti, f.cos_t);
            s.pdf = 1.f - f.r;
            s.eta = f.eta_it;
            s.sampled_lobe = kBsdfDeltaTransmission;
            s.weight = specular_transmittance_->eval(hit);  // no 1/eta^2: see the top comment
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
    Dielectric, femto::PluginKind::Bsdf, "dielectric",
    "Smooth dielectric interface (glass, water): Fresnel-weighted reflection and "
    "refraction",
    {{"int_ior", "float|string", "bk7",
      "interior index of refraction (number or name: water, bk7, diamond, ...)"},
     {"ext_ior", "float|string", "air", "exterior index of refraction (number or name)"},
     {"specular_reflectance", "color|texture", "1", "factor on the reflection (physically 1)"},
     {"specular_transmittance", "color|texture", "1", "factor on the transmission (physically 1)"}})
