// equiangular: Kulla & Fajardo's equiangular sampling (2012), the steady-state reference of
// the thesis' Fig. 5.10. On each ray segment through a medium an extra vertex x(r) is placed
// with density proportional to 1 / |x(r) - light|^2, the falloff of a point light's
// irradiance; the connection's time is left to the geometry.
#include "femto/plugin.h"
#include "femto/time_sampling.h"

namespace {

using namespace femto;

class Equiangular final : public ConnectionSampler {
public:
    explicit Equiangular(const Properties&) {}

    double sample(const ConnectionQuery& q, double u) const override {
        return equiangular_sample(q, u);
    }
    double pdf(const ConnectionQuery& q, double r) const override { return equiangular_pdf(q, r); }
};

}  // namespace

FEMTO_PLUGIN(Equiangular, femto::PluginKind::Connection, "equiangular",
             "Equiangular medium vertices for light connections (Kulla & Fajardo 2012), the "
             "steady reference of Fig. 5.10",
             {})
