// conductor: a perfectly smooth metal mirror (Mitsuba's `conductor`).
//
// A delta reflection weighted by the exact unpolarised Fresnel reflectance of a conductor with
// complex index of refraction eta + i k (per RGB channel), relative to an exterior dielectric
// of index ext_eta. One-sided like Mitsuba's: nothing is reflected when wi.z <= 0 (use
// `twosided`). eval() and pdf() are zero: a delta lobe is only reachable through sample().
//
// Differences from Mitsuba: presets are RGB triples (femto renders in linear RGB); `ext_eta`
// (Mitsuba 0.6's extEta, absent in Mitsuba 3) defaults to 1 like Mitsuba 3's behaviour, where
// Mitsuba 0.6 used air (1.000277, a 0.03% change of the reflectance). The default material is
// Mitsuba 3's "none" (Mitsuba 0.6 defaulted to Cu).
#include <memory>
#include <optional>
#include <string>

#include "femto/bsdf.h"
#include "femto/fresnel.h"
#include "femto/plugin.h"
#include "femto/texture.h"

namespace {

using namespace femto;

class Conductor final : public Bsdf {
public:
    explicit Conductor(const Properties& props)
        : ior_(read_conductor_ior(props)),
          specular_reflectance_(get_texture(props, "specular_reflectance", Color(1.f))) {}

    uint32_t flags() const override { return kBsdfDeltaReflection; }

    BsdfSample sample(const Hit& hit, const Vec3& wi, float, Vec2) const override {
        BsdfSample s;
        if (wi.z <= 0.f) return s;
        s.wo = Vec3(-wi.x, -wi.y, wi.z);
        s.pdf = 1.f;
        s.eta = 1.f;
        s.sampled_lobe = kBsdfDeltaReflection;
        s.weight = specular_reflectance_->eval(hit) * ior_.fresnel(wi.z);
        return s;
    }

    Color eval(const Hit&, const Vec3&, const Vec3&) const override { return Color(0.f); }
    float pdf(const Hit&, const Vec3&, const Vec3&) const override { return 0.f; }

private:
    ConductorIor ior_;
    std::shared_ptr<Texture> specular_reflectance_;
};

}  // namespace

FEMTO_PLUGIN(Conductor, femto::PluginKind::Bsdf, "conductor",
             "Smooth conductor (metal mirror) with exact complex Fresnel reflectance",
             {{"material", "string", "none",
               "conductor preset (Au, Ag, Al, Cu, Cr, W, ...; \"none\" = ideal mirror)"},
              {"eta", "color", "0", "real part of the complex IOR (instead of a preset)"},
              {"k", "color", "1", "imaginary part (absorption) of the complex IOR"},
              {"ext_eta", "float|string", "1", "IOR of the exterior dielectric (number or name)"},
              {"specular_reflectance", "color|texture", "1",
               "factor on the reflection (physically 1)"}})
