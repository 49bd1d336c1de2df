// femto public API: integrators. The host's renderer runs passes over image tiles and calls
// sample() once per camera sample; the integrator reports each radiance contribution with
// its optical path length (so the same integrator feeds steady and transient films).
#pragma once

#include <cstdint>
#include <vector>

#include "femto/film.h"
#include "femto/math.h"
#include "femto/object.h"
#include "femto/sampler.h"
#include "femto/scene.h"

namespace femto {

class Integrator : public Object {
public:
    PluginKind kind() const override { return PluginKind::Integrator; }
    /// Called once before rendering, after the scene is built.
    virtual void preprocess(const Scene& /*scene*/) {}
    /// Estimates the radiance arriving along the camera ray `ray` (unit direction).
    virtual void sample(const Scene& scene, Sampler& sampler, const Ray& ray,
                        ContributionList& out) const = 0;
};

/// Base of integrators that follow paths of bounded depth (Mitsuba's MonteCarloIntegrator):
/// reads `max_depth`, `rr_depth` and `hide_emitters`, so that every such integrator spells them
/// the same way.
class MonteCarloIntegrator : public Integrator {
public:
    /// max_depth, rr_depth (default 5; a plugin lists its own entry to change that) and
    /// hide_emitters.
    static std::vector<ParamSpec> inherited_params();
    /// Longest path in segments (1 = emitters seen directly, 2 = direct light); -1 = none.
    int64_t max_depth() const { return max_depth_; }
    /// Depth from which Russian roulette may end paths; 0 = never.
    int64_t rr_depth() const { return rr_depth_; }
    /// Whether emitters seen directly by the camera are left out.
    bool hide_emitters() const { return hide_emitters_; }
    /// True when a path with `depth` segments may not be extended.
    bool depth_exhausted(int64_t depth) const { return max_depth_ >= 0 && depth >= max_depth_; }
    /// Refuses unbounded paths (max_depth -1 and no roulette) without a finite time window:
    /// nothing would end them.
    void preprocess(const Scene& scene) override;

protected:
    /// `default_rr_depth` is the plugin's default for rr_depth (0: no roulette).
    MonteCarloIntegrator(const Properties& props, int64_t default_rr_depth);

private:
    int64_t max_depth_ = -1, rr_depth_ = 0;
    bool hide_emitters_ = false;
    SourceLocation location_;  // of max_depth (or of the integrator), for preprocess' error
};

}  // namespace femto
