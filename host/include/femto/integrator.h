// femto public API: integrators. The host's renderer runs passes over image tiles and calls
// sample() once per camera sample; the integrator reports each radiance contribution with
// its optical path length (so the same integrator feeds steady and transient films).
#pragma once

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

}  // namespace femto
