// time: time-uniform angular sampling (thesis ch. 5.6.3, eq. 5.26-5.27, appendix 5.C.3). At a
// medium vertex the distance r to the next vertex is drawn first; the direction is then chosen
// so that the length r + |x_next - light| of the path to a light, and so its time, is uniform
// over its range. Directions toward the light are favoured, which keeps paths inside the
// film's window. With no finite light point to aim at it samples the phase function.
#include "femto/plugin.h"
#include "femto/time_sampling.h"

namespace {

using namespace femto;

class TimeAngular final : public AngularSampler {
public:
    explicit TimeAngular(const Properties&) {}

    Vec3 sample(const AngularQuery& q, Vec2 u) const override { return time_sample(q, u); }
    double pdf(const AngularQuery& q, const Vec3& wo) const override { return time_pdf(q, wo); }
};

}  // namespace

FEMTO_PLUGIN(TimeAngular, femto::PluginKind::Angular, "time",
             "Time-uniform angular sampling at medium vertices, aimed at a light (ch. 5.6.3, "
             "eq. 5.26-5.27)",
             {})
