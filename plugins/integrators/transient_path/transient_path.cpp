// Transient path tracing (thesis ch. 5.4): unidirectional path tracing with next-event
// estimation and MIS in which every contribution lands at its own path time (NEE and
// BSDF-sampled emitter hits arrive at different times). No Russian roulette: a path ends when
// its time passes the film's end or at max_depth (ch. 5.6.1). Every vertex's contributions
// reach the film in the same pass (path reuse in time, ch. 5.4.1).
//
// In participating media three nested strategies (ch. 5.6) decide when samples land:
// <distance> how far paths travel between medium vertices (`mean_free_path`, the default, or
// the time-uniform `exponential`), <connection> whether an extra medium vertex carries each
// segment's light connection (`deterministic`, the default, `line_to_point` or
// `equiangular`), and <angular> the direction out of a medium vertex (`phase`, the default,
// or `time`). `mis` combines each with its steady counterpart.
#include <fmt/format.h>

#include <cmath>

#include "femto/integrator.h"
#include "femto/path_tracer.h"
#include "femto/plugin.h"
#include "femto/sensor.h"
#include "femto/time_sampling.h"

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
        distance_ = strategy<DistanceSampler>(props, PluginKind::Distance, "distance");
        connection_ = strategy<ConnectionSampler>(props, PluginKind::Connection, "connection");
        angular_ = strategy<AngularSampler>(props, PluginKind::Angular, "angular");
        options_.distance = distance_.get();
        options_.connection = connection_.get();
        options_.angular = angular_.get();
        options_.mis = props.get_bool("mis", false);
    }

    void preprocess(const Scene& scene) override {
        if (options_.max_depth < 0 && !std::isfinite(scene.sensor().film().max_path_length()))
            throw SceneError(
                "transient_path with max_depth=-1 needs a film with a finite time window "
                "(a transient or streak film); set max_depth for steady films");
        if (distance_) distance_->prepare({scene.sensor().film().max_path_length()});
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& ray,
                ContributionList& out) const override {
        trace_path(scene, sampler, ray, out, options_);
    }

private:
    // The nested strategy of `kind`, or null when none is given (the steady default).
    template <class T>
    static std::shared_ptr<T> strategy(const Properties& props, PluginKind kind, const char* tag) {
        auto objects = props.objects(kind);
        if (objects.size() > 1) props.fail(tag, fmt::format("give at most one <{}> strategy", tag));
        return objects.empty() ? nullptr : std::static_pointer_cast<T>(objects[0]);
    }

    PathTracerOptions options_;
    std::shared_ptr<DistanceSampler> distance_;
    std::shared_ptr<ConnectionSampler> connection_;
    std::shared_ptr<AngularSampler> angular_;
};

}  // namespace

FEMTO_PLUGIN(TransientPath, femto::PluginKind::Integrator, "transient_path",
             "Transient path tracer: NEE + MIS, each contribution at its own time, no roulette",
             {{"max_depth", "integer", "-1",
               "longest path in segments; -1 = until the film's time window ends"},
              {"hide_emitters", "boolean", "false", "hide directly visible emitters"},
              {"distance", "distance", "mean_free_path",
               "distance sampling in media (nested <distance>): mean_free_path or exponential"},
              {"connection", "connection", "deterministic",
               "light connections in media (nested <connection>): deterministic, "
               "line_to_point or equiangular"},
              {"angular", "angular", "phase",
               "directions at medium vertices (nested <angular>): phase or time"},
              {"mis", "boolean", "false",
               "combine each time strategy with its steady counterpart by MIS"}})
