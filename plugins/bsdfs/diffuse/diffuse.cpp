// diffuse: the ideal Lambertian reflector (Mitsuba's `diffuse`).
//
// f = reflectance / pi on the front side only (wi.z > 0 and wo.z > 0); wrap it in `twosided`
// to make both sides reflect. Sampling is cosine-weighted, so the sample weight is exactly the
// reflectance.
#include <memory>

#include "femto/bsdf.h"
#include "femto/plugin.h"
#include "femto/texture.h"
#include "femto/warp.h"

namespace {

using namespace femto;

class Diffuse final : public Bsdf {
public:
    explicit Diffuse(const Properties& props)
        : reflectance_(get_texture(props, "reflectance", Color(0.5f))) {}

    uint32_t flags() const override { return kBsdfDiffuseReflection; }

    BsdfSample sample(const Hit& hit, const Vec3& wi, float /*u_lobe*/, Vec2 u) const override {
        return sample_lambertian(wi, u, reflectance_->eval(hit));
    }

    Color eval(const Hit& hit, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return Color(0.f);
        return reflectance_->eval(hit) * (wo.z * kInvPi);
    }

    float pdf(const Hit&, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return 0.f;
        return warp::cosine_hemisphere_pdf(wo);
    }

private:
    std::shared_ptr<Texture> reflectance_;
};

}  // namespace

FEMTO_PLUGIN(Diffuse, femto::PluginKind::Bsdf, "diffuse",
             "Ideal diffuse (Lambertian) reflector, front side only",
             {{"reflectance", "color|texture", "0.5",
               "albedo of the surface (fraction of light reflected)"}})
