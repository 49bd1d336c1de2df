// femto public API: the unidirectional path tracer shared by the `path` and `transient_path`
// integrators, reusable by plugins that need a path-traced estimate.
#pragma once

#include <cstdint>

#include "femto/film.h"
#include "femto/sampler.h"
#include "femto/scene.h"

namespace femto {

struct PathTracerOptions {
    int64_t max_depth = -1;  ///< longest path in segments (1 = emitters seen directly); -1 = none
    int64_t rr_depth = 5;    ///< depth at which Russian roulette starts; 0 = never
    bool hide_emitters = false;  ///< drop emission seen directly by the camera
    /// Distance sampling in media (ch. 5.6.1); nullptr = mean free path.
    const class DistanceSampler* distance = nullptr;
    /// Connection strategy in media (ch. 5.6.2); nullptr = deterministic shadow rays only.
    /// A strategy that places vertices adds, on every ray segment through a medium, an extra
    /// vertex connected to a light; it takes over the light connections of the distance
    /// strategy's vertices on that segment (or shares them by MIS, see `mis`).
    const class ConnectionSampler* connection = nullptr;
    /// Angular sampling at medium vertices (ch. 5.6.3); nullptr = the phase function.
    const class AngularSampler* angular = nullptr;
    /// Combine each time strategy with its steady counterpart by multiple importance sampling
    /// (balance heuristic): `distance` with mean-free-path sampling and `angular` with the
    /// phase function as half-half mixtures, and `connection` vertices with the distance
    /// strategy's shadow rays.
    bool mis = false;
};

/// Traces one camera path with next-event estimation and MIS (power heuristic; at medium
/// vertices with a time angular strategy, light sampling alone, since that strategy's
/// direction density depends on the next distance). Every
/// contribution is reported with its time: the optical path length travelled (each segment
/// times the refractive index it crosses, tracked through dielectric transmissions), plus the
/// emitter's sampled emission time and any scattering delays (eq. 5.11-5.16). Paths stop
/// when their time passes the film's max_path_length() (ch. 5.6.1), at max_depth, or by
/// Russian roulette when enabled. Sets the list's sensor distance at the first hit.
void trace_path(const Scene& scene, Sampler& sampler, const Ray& camera_ray, ContributionList& out,
                const PathTracerOptions& options);

}  // namespace femto
