// Unidirectional path tracer with next-event estimation and multiple importance sampling
// (power heuristic), Mitsuba's `path`, with Russian roulette. The estimator itself is the
// host's trace_path (shared with transient_path); every contribution carries its time, so
// this integrator also feeds transient films.
#include "femto/integrator.h"
#include "femto/path_tracer.h"
#include "femto/plugin.h"

namespace {

using namespace femto;

class PathTracer final : public Integrator {
public:
    explicit PathTracer(const Properties& props) {
        options_.max_depth = props.get_int("max_depth", -1);
        options_.rr_depth = props.get_int("rr_depth", 5);
        options_.hide_emitters = props.get_bool("hide_emitters", false);
        if (options_.max_depth < -1)
            props.fail("max_depth", "max_depth must be -1 (unbounded) or >= 0");
        if (options_.rr_depth < 1) props.fail("rr_depth", "rr_depth must be >= 1");
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& ray,
                ContributionList& out) const override {
        trace_path(scene, sampler, ray, out, options_);
    }

private:
    PathTracerOptions options_;
};

}  // namespace

FEMTO_PLUGIN(PathTracer, femto::PluginKind::Integrator, "path",
             "Unidirectional path tracer with next-event estimation and MIS",
             {{"max_depth", "integer", "-1",
               "longest path (1 = visible emitters only, 2 = direct light; -1 = unbounded)"},
              {"rr_depth", "integer", "5", "path depth at which Russian roulette starts"},
              {"hide_emitters", "boolean", "false", "hide directly visible emitters"}})
