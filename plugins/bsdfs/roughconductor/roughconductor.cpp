// roughconductor: a rough metal described by a microfacet model (Mitsuba's `roughconductor`).
//
// f(wi, wo) = F(wi.h) D(h) G(wi, wo, h) / (4 cos_i cos_o) with h the half vector, Beckmann or
// GGX normal distributions (isotropic or anisotropic), Smith's separable uncorrelated
// shadowing-masking G = G1(wi) G1(wo) and the exact conductor Fresnel term per RGB channel.
// One-sided like Mitsuba's (zero unless wi.z > 0 and wo.z > 0).
//
// Sampling (as Mitsuba): a microfacet normal m from femto::Microfacet (the visible normals, or
// D(m) cos(theta_m) with sample_visible = false; see femto/microfacet.h, which also says where
// its Beckmann G1 differs from Mitsuba's), reflected about m. The reflected direction's pdf is
// p(m) / (4 wo.m). Roughness values below 1e-4 are clamped to 1e-4 (as Mitsuba does).
// Roughness is a float, not a texture.
#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include "femto/bsdf.h"
#include "femto/fresnel.h"
#include "femto/microfacet.h"
#include "femto/plugin.h"
#include "femto/texture.h"

namespace {

using namespace femto;

class RoughConductor final : public Bsdf {
public:
    explicit RoughConductor(const Properties& props)
        : distr_(read_microfacet(props)),
          ior_(read_conductor_ior(props)),
          specular_reflectance_(get_texture(props, "specular_reflectance", Color(1.f))) {}

    uint32_t flags() const override { return kBsdfGlossyReflection; }

    BsdfSample sample(const Hit& hit, const Vec3& wi, float, Vec2 u) const override {
        BsdfSample s;
        if (wi.z <= 0.f) return s;
        Vec3 m;
        if (!distr_.sample(wi, u, m)) return s;
        const float wi_m = dot(wi, m);
        if (!(wi_m > 0.f)) return s;
        const Vec3 wo = reflect(wi, m);
        if (!(wo.z > 0.f)) return s;
        const float pdf = distr_.pdf(wi, m) / (4.f * wi_m);  // wo.m == wi.m
        if (!(pdf > 0.f) || !std::isfinite(pdf)) return s;
        float g;
        if (distr_.sample_visible())
            g = distr_.G1(wo, m);  // D G1(wi) G1(wo) / (4 cos_i) over D G1(wi) / (4 cos_i)
        else
            g = distr_.G1(wi, m) * distr_.G1(wo, m) * wi_m / (wi.z * m.z);
        s.wo = wo;
        s.pdf = pdf;
        s.eta = 1.f;
        s.sampled_lobe = kBsdfGlossyReflection;
        s.weight = specular_reflectance_->eval(hit) * ior_.fresnel(wi_m) * g;
        return s;
    }

    Color eval(const Hit& hit, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return Color(0.f);
        const Vec3 h = normalize(wi + wo);
        const float d = distr_.D(h);
        if (d == 0.f) return Color(0.f);
        const float g = distr_.G1(wi, h) * distr_.G1(wo, h);
        return specular_reflectance_->eval(hit) * ior_.fresnel(dot(wi, h)) * (d * g / (4.f * wi.z));
    }

    float pdf(const Hit&, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return 0.f;
        const Vec3 h = normalize(wi + wo);
        const float wo_h = dot(wo, h);
        if (!(dot(wi, h) > 0.f) || !(wo_h > 0.f)) return 0.f;
        return distr_.pdf(wi, h) / (4.f * wo_h);
    }

private:
    Microfacet distr_;
    ConductorIor ior_;
    std::shared_ptr<Texture> specular_reflectance_;
};

}  // namespace

FEMTO_PLUGIN(RoughConductor, femto::PluginKind::Bsdf, "roughconductor",
             "Rough conductor: Beckmann/GGX microfacet model with complex Fresnel reflectance",
             {{"distribution", "string", "beckmann", "microfacet distribution: beckmann or ggx"},
              {"alpha", "float", "0.1", "isotropic roughness (RMS slope for beckmann)"},
              {"alpha_u", "float", "",
               "anisotropic roughness along the tangent (with alpha_v, instead of alpha)"},
              {"alpha_v", "float", "",
               "anisotropic roughness along the bitangent (with alpha_u, instead of alpha)"},
              {"sample_visible", "boolean", "true",
               "sample the visible normals (else the full distribution)"},
              {"material", "string", "none",
               "conductor preset (Au, Ag, Al, Cu, Cr, W, ...; \"none\" = ideal mirror)"},
              {"eta", "color", "0", "real part of the complex IOR (instead of a preset)"},
              {"k", "color", "1", "imaginary part (absorption) of the complex IOR"},
              {"ext_eta", "float|string", "1", "IOR of the exterior dielectric (number or name)"},
              {"specular_reflectance", "color|texture", "1",
               "factor on the reflection (physically 1)"}})
