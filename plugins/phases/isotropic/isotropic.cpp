// isotropic: the isotropic phase function (Mitsuba's `isotropic`), 1 / (4 pi) for every pair of
// directions; sample() draws wo uniformly over the sphere, so its weight is exactly 1.
#include "femto/medium.h"
#include "femto/plugin.h"
#include "femto/warp.h"

namespace {

class IsotropicPhase final : public femto::PhaseFunction {
public:
    explicit IsotropicPhase(const femto::Properties&) {}

    float eval(const femto::Vec3&, const femto::Vec3&) const override {
        return femto::warp::uniform_sphere_pdf();
    }

    femto::Vec3 sample(const femto::Vec3&, femto::Vec2 u) const override {
        return femto::warp::square_to_uniform_sphere(u);
    }
};

}  // namespace

FEMTO_PLUGIN(IsotropicPhase, femto::PluginKind::Phase, "isotropic",
             "Isotropic phase function: 1 / (4 pi) in every direction", {})
