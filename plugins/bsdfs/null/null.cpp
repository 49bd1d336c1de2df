// null: an index-matched boundary that does not interact with light (Mitsuba's `null`).
//
// Used for medium boundaries: sample() continues the path straight through (wo = -wi) with
// weight 1; integrators recognise it through Bsdf::is_null() and do not count the crossing
// as a scattering event.
#include "femto/bsdf.h"
#include "femto/plugin.h"

namespace {

using namespace femto;

class NullBsdf final : public Bsdf {
public:
    explicit NullBsdf(const Properties& /*props*/) {}

    uint32_t flags() const override { return kBsdfNull; }

    BsdfSample sample(const Hit&, const Vec3& wi, float, Vec2) const override {
        BsdfSample s;
        s.wo = -wi;
        s.pdf = 1.f;
        s.eta = 1.f;
        s.sampled_lobe = kBsdfNull;
        s.weight = Color(1.f);
        return s;
    }

    Color eval(const Hit&, const Vec3&, const Vec3&) const override { return Color(0.f); }
    float pdf(const Hit&, const Vec3&, const Vec3&) const override { return 0.f; }
};

}  // namespace

FEMTO_PLUGIN(NullBsdf, femto::PluginKind::Bsdf, "null",
             "Index-matched pass-through boundary (for medium interfaces)", {})
