// deterministic: the steady-state shadow connection. No extra vertex is placed; the
// integrator casts its ordinary shadow ray from each vertex the distance strategy places, so
// the connection's duration is whatever the geometry makes it (ch. 5.6.2).
#include "femto/plugin.h"
#include "femto/time_sampling.h"

namespace {

using namespace femto;

class Deterministic final : public ConnectionSampler {
public:
    explicit Deterministic(const Properties&) {}

    bool places_vertex() const override { return false; }
    double sample(const ConnectionQuery&, double) const override { return -1.0; }
    double pdf(const ConnectionQuery&, double) const override { return 0.0; }
};

}  // namespace

FEMTO_PLUGIN(Deterministic, femto::PluginKind::Connection, "deterministic",
             "Steady shadow connections: a shadow ray from every vertex the distance strategy "
             "places (ch. 5.6.2)",
             {})
