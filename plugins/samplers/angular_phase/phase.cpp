// phase: steady-state angular sampling, the medium's phase function (ch. 5.6.3).
#include "femto/plugin.h"
#include "femto/time_sampling.h"

namespace {

using namespace femto;

class PhaseSampling final : public AngularSampler {
public:
    explicit PhaseSampling(const Properties&) {}

    bool steady() const override { return true; }
    Vec3 sample(const AngularQuery& q, Vec2 u) const override { return q.phase->sample(q.wi, u); }
    double pdf(const AngularQuery& q, const Vec3& wo) const override {
        return double(q.phase->eval(q.wi, wo));
    }
};

}  // namespace

FEMTO_PLUGIN(PhaseSampling, femto::PluginKind::Angular, "phase",
             "Steady angular sampling: directions drawn from the medium's phase function", {})
