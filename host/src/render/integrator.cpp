// MonteCarloIntegrator: the parameters every path-following integrator shares.
#include "femto/integrator.h"

#include <cmath>
#include <stdexcept>

#include "femto/error.h"
#include "femto/properties.h"

namespace femto {

void Integrator::sample(const Scene&, Sampler&, const Ray&, ContributionList&) const {
    throw std::logic_error(type_name() + " has no camera samples (it does not implement sample())");
}

void Integrator::sample_light(const Scene&, Sampler&, SplatList&) const {
    throw std::logic_error(type_name() +
                           " traces no light paths (it does not implement "
                           "sample_light())");
}

std::vector<ParamSpec> MonteCarloIntegrator::inherited_params() {
    return inherit_params(
        Integrator::inherited_params(), "MonteCarloIntegrator",
        {{"max_depth", "integer", "-1",
          "longest path in segments (1 = emitters seen directly, 2 = direct light; -1 = no "
          "limit)"},
         {"rr_depth", "integer", "5", "path depth at which Russian roulette starts; 0 = never"},
         {"hide_emitters", "boolean", "false", "hide emitters the camera sees directly"}});
}

MonteCarloIntegrator::MonteCarloIntegrator(const Properties& props, int64_t default_rr_depth)
    : max_depth_(props.get_int("max_depth", -1)),
      rr_depth_(props.get_int("rr_depth", default_rr_depth)),
      hide_emitters_(props.get_bool("hide_emitters", false)),
      location_(props.location_of("max_depth")) {
    if (max_depth_ < -1) props.fail("max_depth", "max_depth must be -1 (unbounded) or >= 0");
    if (rr_depth_ < 0) props.fail("rr_depth", "rr_depth must be >= 1, or 0 for no roulette");
}

void MonteCarloIntegrator::preprocess(const Scene& scene) {
    if (max_depth_ < 0 && rr_depth_ == 0 && !scene.time_window().bounded())
        throw SceneError(location_,
                         type_name() +
                             " with max_depth=-1 and no Russian roulette (rr_depth=0) needs a "
                             "time window that ends its paths (a transient or streak film with "
                             "prune_paths on); set max_depth or rr_depth otherwise");
}

}  // namespace femto
