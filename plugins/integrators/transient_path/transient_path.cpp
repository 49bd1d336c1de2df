// Transient path tracing (thesis ch. 5.4): unidirectional path tracing with next-event
// estimation and MIS in which every contribution lands at its own path time (NEE and
// BSDF-sampled emitter hits arrive at different times). No Russian roulette: a path ends when
// its time passes the film's end or at max_depth (ch. 5.6.1). Every vertex's contributions
// reach the film in the same pass (path reuse in time, ch. 5.4.1).
#include <cmath>

#include "femto/integrator.h"
#include "femto/path_tracer.h"
#include "femto/plugin.h"
#include "femto/sensor.h"

namespace {

using namespace femto;

class TransientPath final : public Integrator {
public:
    explicit TransientPath(const Properties& props) {
        options_.max_depth = props.get_int("max_depth", -1);
        options_.rr_depth = 0;  // time, not roulette, bounds transient paths
        options_.hide_emitters = props.get_bool("hide_emitters", false);
        if (options_.max_depth < -1)
            props.fail("max_depth", "max_depth must be -1 (unbounded) or >= 0");
    }

    void preprocess(const Scene& scene) override {
        if (options_.max_depth < 0 && !std::isfinite(scene.sensor().film().max_path_length()))
            throw SceneError(
                "transient_path with max_depth=-1 needs a film with a finite time window "
                "(a transient or streak film); set max_depth for steady films");
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& ray,
                ContributionList& out) const override {
        trace_path(scene, sampler, ray, out, options_);
    }

private:
    PathTracerOptions options_;
};

}  // namespace

FEMTO_PLUGIN(TransientPath, femto::PluginKind::Integrator, "transient_path",
             "Transient path tracer: NEE + MIS, each contribution at its own time, no roulette",
             {{"max_depth", "integer", "-1",
               "longest path in segments; -1 = until the film's time window ends"},
              {"hide_emitters", "boolean", "false", "hide directly visible emitters"}})
