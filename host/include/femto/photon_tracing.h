// femto public API: photon paths for density estimators (progressive photon mapping, photon
// beams; thesis ch. 5.5 and 5.7). A photon path is a light path that an estimator keeps pieces
// of: photons at its vertices, beams along its segments through media. trace_photon_path()
// walks one such path with the light tracer's rules (pulses, delays, eta, adjoint shading
// factors, mean-free-path sampling in media, Russian roulette) and tells a visitor what it
// crosses; trace_photon_paths() traces a pass's paths in parallel, in fixed chunks whose
// results the caller appends in chunk order, so that what is stored does not depend on the
// thread count.
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "femto/integrator.h"
#include "femto/medium.h"
#include "femto/path_clock.h"
#include "femto/random.h"
#include "femto/sensor.h"
#include "femto/time_sampling.h"
#include "femto/transport.h"

namespace femto {

/// Everything a photon path carries from vertex to vertex.
struct PhotonPath {
    Ray ray;           ///< the segment being traced (from the last vertex)
    LightClock clock;  ///< at the last vertex
    MediumTracker medium;
    Color power;        ///< flux the path carries (emitted / densities / paths per pass)
    float start = 1.f;  ///< its largest channel at the emitter, for Russian roulette
    int64_t depth = 1;  ///< segments so far, the one being traced included
    /// Mean-free-path distances, in the medium crossed last.
    DistanceMixtureCache free_paths{};
};

/// The free flight of a photon path through a medium (PhotonVisitor::medium_segment()).
struct FreeFlight {
    const Medium* medium = nullptr;
    double length = 0;  ///< to the medium vertex, or to the surface that ends the segment
    bool scattered = false;
    /// Rate of the exponential the distance was drawn with: the path passes distance t < length
    /// with probability exp(-rate t) (DistanceSampler::mean_free_path_rate()).
    double rate = 0;
};

/// What a density estimator keeps of a photon path; each hook is optional (the defaults do
/// nothing). `path` is the state on arrival: its clock at the vertex, its power what arrives.
struct PhotonVisitor {
    /// At a surface vertex whose material has a smooth lobe, before the path scatters there.
    void surface(const Hit& /*hit*/, const PhotonPath& /*path*/) {}
    /// A segment through a medium, traced from path.ray's origin with the power path.power
    /// that entered it (before the flight's weight), the clock still at its start.
    void medium_segment(const PhotonPath& /*path*/, const FreeFlight& /*flight*/) {}
    /// At a medium vertex, the clock there and the power weighted by the distance sample.
    void medium_vertex(const PhotonPath& /*path*/) {}
};

namespace detail {

/// Russian roulette from the integrator's rr_depth on the share of the emitted power the path
/// still carries; then the path has one more segment. False when the path ends.
inline bool photon_continues(const MonteCarloIntegrator& rules, Sampler& sampler,
                             PhotonPath& path) {
    const float survived =
        rules.roulette(path.depth, path.power.max_component() / path.start, sampler);
    if (survived == 0.f) return false;
    path.power *= survived;
    ++path.depth;
    return true;
}

/// Whether anything at a vertex reached after `depth` segments can still join a camera path of
/// at least one segment within the integrator's max_depth.
inline bool photon_useful(const MonteCarloIntegrator& rules, int64_t depth) {
    return rules.max_depth() < 0 || depth + 1 <= rules.max_depth();
}

enum class FlightEnd { Surface, Scattered, Stop };

// The path crosses a medium toward `hit` (if `found`): a distance by the mean free path
// decides whether it scatters first; there it goes on in a direction drawn from the phase
// function (weight 1).
template <typename Visitor>
FlightEnd photon_in_medium(const MonteCarloIntegrator& rules, Sampler& sampler, PhotonPath& path,
                           bool found, const Hit& hit, Visitor& visitor) {
    const Medium& medium = *path.medium.medium;
    const DistanceMixture& free_path = path.free_paths(medium);
    const double tmax = found ? double(hit.t) : kInfinity;
    const double u = double(sampler.next_1d());
    const DistanceSample ds = sample_distance(medium, path.ray, tmax, free_path, u, sampler);
    visitor.medium_segment(path, FreeFlight{&medium, ds.scattered ? ds.distance : tmax,
                                            ds.scattered, free_path.steady_rate()});
    path.power *= ds.weight;
    if (path.power.is_black()) return FlightEnd::Stop;
    if (!ds.scattered) return found ? FlightEnd::Surface : FlightEnd::Stop;
    path.clock.travel_to(path.ray.at(float(ds.distance)), medium.eta());
    if (path.clock.expired()) return FlightEnd::Stop;
    visitor.medium_vertex(path);
    if (!photon_useful(rules, path.depth + 1)) return FlightEnd::Stop;
    const Vec3 x = path.clock.position(), wi = -path.ray.d;
    path.ray = Ray{x, medium.phase().sample(wi, sampler.next_2d()), 0.f, kInfinity};
    return photon_continues(rules, sampler, path) ? FlightEnd::Scattered : FlightEnd::Stop;
}

}  // namespace detail

/// Traces one photon path from an emitter chosen by `starts` (prepared for the scene), carrying
/// its start's power times `scale` (1 / paths per pass), until it ends (window, `rules`'
/// max_depth and roulette, escape), and tells `visitor` (a PhotonVisitor's hooks) what it
/// crosses. Random numbers come from `sampler` in a fixed order.
template <typename Visitor>
void trace_photon_path(const Scene& scene, const LightPathStarts& starts,
                       const MonteCarloIntegrator& rules, Sampler& sampler, double scale,
                       Visitor& visitor) {
    const LightPathStarts::Start start = LightPathStarts::sample(scene, sampler);
    if (!start) return;
    const EmissionSample& es = start.emission;
    PhotonPath path{emission_ray(es), LightClock(scene, *start.emitter, es.p, sampler),
                    starts.medium(*start.emitter, es, es.d), start.power() * float(scale)};
    path.start = path.power.max_component();
    Hit hit;  // one for every vertex: Scene::intersect() sets all of it
    while (detail::photon_useful(rules, path.depth)) {
        const bool found = scene.intersect(path.ray, hit);
        if (path.medium.medium) {
            const auto end = detail::photon_in_medium(rules, sampler, path, found, hit, visitor);
            if (end == detail::FlightEnd::Scattered) continue;
            if (end == detail::FlightEnd::Stop) return;
        }
        if (!found) return;
        const Bsdf& bsdf = *hit.shape->bsdf();
        path.clock.travel_to(hit.p, path.medium.eta());
        if (path.clock.expired()) return;
        if (bsdf.is_null()) {  // an index-matched boundary: not a scattering event
            path.medium.cross(hit, path.ray.d);
            path.ray = hit.spawn(path.ray.d);
            continue;
        }
        if (bsdf.flags() & kBsdfSmooth) visitor.surface(hit, path);
        if (!detail::photon_useful(rules, path.depth + 1)) return;
        const VertexEvent event = apply_vertex_event(bsdf, hit, sampler, path.clock);
        const float u_lobe = sampler.next_1d();
        const BsdfSample bs = sample_adjoint(bsdf, hit, hit.wi, u_lobe, sampler.next_2d());
        if (!bs.valid() || bs.weight.is_black()) return;
        const Vec3 wo = hit.to_world(bs.wo);
        path.power =
            leaving(event, bs.weight * path.power) * adjoint_shading_factor(hit, -path.ray.d, wo);
        if (path.power.is_black()) return;
        path.medium.refract(bs);
        path.medium.cross(hit, wo);
        path.ray = hit.spawn(wo);
        if (!detail::photon_continues(rules, sampler, path)) return;
    }
}

/// Photon paths are traced in chunks of this many.
constexpr uint64_t kPhotonChunk = 1024;

/// Traces `paths` photon paths of pass `pass` in parallel: `chunks` is resized to one Chunk per
/// kPhotonChunk paths, each emptied first, and trace(sampler, chunk) is called for each path
/// with the sampler started for it (its own seed, the path's index, the pass), so that each
/// path's random numbers depend only on its index and the caller, appending the chunks in
/// order, stores the same things whatever the thread count. A Chunk with a clear() member is
/// emptied by it and so keeps its storage from pass to pass (freeing and allocating it again
/// every pass costs page faults: bench/README.md, "Photon storage kept across passes"); any
/// other Chunk is replaced by a default-constructed one.
template <typename Chunk, typename Trace>
void trace_photon_paths(const Scene& scene, const PassInfo& pass, uint64_t paths,
                        std::vector<Chunk>& chunks, Trace&& trace) {
    const uint64_t count = (paths + kPhotonChunk - 1) / kPhotonChunk;
    chunks.resize(size_t(count));
    // Photon streams: another seed than the camera samples', the pass as the sample index.
    const uint64_t seed = mix64(pass.seed ^ 0x70686f746f6e73ull);
    const Sampler& prototype = scene.sensor().sampler();
    tbb::parallel_for(uint64_t(0), count, [&](uint64_t c) {
        std::unique_ptr<Sampler> sampler = prototype.clone();
        Chunk& into = chunks[size_t(c)];
        if constexpr (requires { into.clear(); })
            into.clear();
        else
            into = Chunk{};
        const uint64_t end = std::min(paths, (c + 1) * kPhotonChunk);
        for (uint64_t i = c * kPhotonChunk; i < end; ++i) {
            sampler->start(seed, i, pass.pass);
            trace(*sampler, into);
        }
    });
}

}  // namespace femto
