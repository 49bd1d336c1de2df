// path and transient_path: unidirectional (volumetric) path tracing with next-event estimation
// and multiple importance sampling, every contribution at its own time of flight (thesis
// ch. 5.4, eq. 5.11-5.16). One estimator, built into two plugins that differ only in their
// defaults: `path` (Mitsuba's) ends paths by Russian roulette from rr_depth 5; `transient_path`
// uses no roulette by default, since the film's time window bounds transient paths
// (ch. 5.6.1). Both feed steady and transient films alike.
//
// A camera path alternates two kinds of step, each a function below:
//   - medium_segment(): in a medium, the segment up to the next surface may hold a connection
//     strategy's vertex (connection_vertex()) and a medium vertex drawn by the distance
//     strategy (medium_vertex(): light sample, then a direction by the angular strategy);
//   - surface_vertex(): an emitter the path hit (emitter_hit()), null boundaries passed, the
//     material's vertex event, a light sample (surface_light()), a BSDF sample to continue,
//     and Russian roulette.
// Three nested strategies (ch. 5.6) decide when samples land in media: <distance> how far paths
// travel between medium vertices (`mean_free_path`, the default, or the time-uniform
// `exponential`), <connection> whether an extra vertex on each segment carries its light
// connection (`deterministic`, the default, `line_to_point` or `equiangular`) and <angular>
// the direction out of a medium vertex (`phase`, the default, or `time`); `mis` combines
// each with its steady counterpart.
//
// Time: PathClock (femto/path_clock.h) owns every time rule; the pieces this file is built
// from are in femto/transport.h and femto/mis.h.
#include <algorithm>
#include <cmath>
#include <memory>

#include "femto/integrator.h"
#include "femto/mis.h"
#include "femto/path_clock.h"
#include "femto/plugin.h"
#include "femto/time_sampling.h"
#include "femto/transport.h"

namespace {

using namespace femto;

// Everything one camera path carries from vertex to vertex.
struct PathState {
    Ray ray;
    PathClock clock;
    MediumTracker medium;
    Throughput throughput;
    int64_t depth = 1;  // segments so far, the one being traced included
    // For MIS of emitters the path hits: where its last direction was chosen, that choice's
    // density, whether it was a delta, and the share of direct light such hits carry (a
    // connection vertex or a time-angular vertex takes the rest).
    Vec3 prev_p;
    float prev_pdf = 1.f;
    bool prev_delta = true;
    float hit_share = 1.f;
    // The light point the connection and angular strategies aim at: the latest one sampled for
    // next-event estimation (any point chosen before a segment's distances are drawn keeps them
    // unbiased).
    bool has_target = false;
    Vec3 target;
    double next_u = -1.0;  // the next distance's uniform number, when drawn ahead (angular=time)
    DistanceMixtureCache distances;  // the distance strategy in the medium travelled last

    PathState(const Scene& scene, const Ray& camera_ray, ContributionList& out,
              const DistanceSampler* distance, bool mis)
        : ray(camera_ray),
          clock(scene, out, camera_ray.o),
          medium(MediumTracker::at_sensor(scene)),
          prev_p(camera_ray.o),
          distances(distance, mis, DistanceContext{clock.window().end}) {}
    void aim_at(const EmitterSample& light) {
        if (light.pdf > 0 && std::isfinite(light.distance)) {
            target = light.p;
            has_target = true;
        }
    }
};

// What a segment through a medium ended in.
enum class SegmentEnd { Surface, Scattered, Stop };

class PathIntegrator : public MonteCarloIntegrator {
public:
    PathIntegrator(const Properties& props, int64_t default_rr_depth)
        : MonteCarloIntegrator(props, default_rr_depth) {
        // The nested strategies; the defaults are the steady ones.
        distance_ = std::static_pointer_cast<DistanceSampler>(
            props.child(PluginKind::Distance, "mean_free_path"));
        connection_ = std::static_pointer_cast<ConnectionSampler>(
            props.child(PluginKind::Connection, "deterministic"));
        angular_ =
            std::static_pointer_cast<AngularSampler>(props.child(PluginKind::Angular, "phase"));
        mis_ = props.get_bool("mis", false);
        connecting_ = connection_->places_vertex();
        steady_angular_ = angular_->steady();
    }

    void preprocess(const Scene& scene) override {
        MonteCarloIntegrator::preprocess(scene);
        distance_->prepare({scene.time_window().end});
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& ray,
                ContributionList& out) const override {
        if (max_depth() == 0) return;
        PathState path(scene, ray, out, distance_.get(), mis_);
        Hit hit;  // one for every vertex: intersect() sets all of it
        for (;;) {
            const bool found = scene.intersect(path.ray, hit);
            if (path.medium.medium) {
                const SegmentEnd end = medium_segment(scene, sampler, path, found, hit);
                if (end == SegmentEnd::Scattered) continue;
                if (end == SegmentEnd::Stop) return;
            }
            if (!found) {  // the environment (MIS against the light samples)
                if (path.depth > 1 || !hide_emitters())
                    record_environment(scene, sampler, path.clock, path.throughput, path.ray.d,
                                       path.medium.eta(), path.prev_pdf, path.prev_delta,
                                       path.hit_share);
                return;
            }
            if (!surface_vertex(scene, sampler, path, hit)) return;
        }
    }

private:
    // ---- surfaces ----------------------------------------------------------------------------

    // The path reaches surface `hit`. Returns false when it ends there.
    bool surface_vertex(const Scene& scene, Sampler& sampler, PathState& path, Hit& hit) const {
        const Bsdf& bsdf = *hit.shape->bsdf();
        path.clock.travel_to(hit.p, path.medium.eta());
        if (!bsdf.is_null()) path.clock.reach_vertex();
        if (path.clock.expired()) return false;
        if (const Emitter* emitter = hit.shape->emitter())
            emitter_hit(scene, sampler, path, hit, *emitter);
        if (bsdf.is_null()) {  // an index-matched boundary: not a scattering event
            path.medium.cross(hit, path.ray.d);
            path.ray = hit.spawn(path.ray.d);
            return true;
        }
        if (depth_exhausted(path.depth)) return false;
        // The vertex's event (delay, colour transfer) applies to everything leaving it.
        apply_vertex_event(bsdf, hit, sampler, path.clock, path.throughput);
        if (bsdf.flags() & kBsdfSmooth) surface_light(scene, sampler, path, hit, bsdf);
        return continue_from_surface(sampler, path, hit, bsdf);
    }

    // Emission seen by the path, weighted by MIS against the light sample that could have
    // found it from the previous vertex.
    void emitter_hit(const Scene& scene, Sampler& sampler, PathState& path, const Hit& hit,
                     const Emitter& emitter) const {
        const Color Le = emitter.eval(hit, -path.ray.d);
        if (Le.is_black() || (path.depth == 1 && hide_emitters())) return;
        float w = 1.f;
        if (!path.prev_delta)
            w = path.hit_share *
                power_heuristic(path.prev_pdf, scene.pdf_emitter(emitter, path.prev_p, hit));
        path.clock.record(path.throughput(Le * w), emitter, sampler);
    }

    // Next-event estimation at a surface: one light sample and its shadow connection; the
    // light arrives over the connection's optical length. (The sample also tells a camera
    // ray's hit which light directions it stands for: PixelFootprint::light_cone.)
    void surface_light(const Scene& scene, Sampler& sampler, PathState& path, Hit& hit,
                       const Bsdf& bsdf) const {
        const EmitterSample light = sample_emitter(scene, hit, sampler);
        if (light.pdf > 0 && !light.weight.is_black()) {
            const Vec3 wo = hit.to_local(light.wi);
            const Color f = bsdf.eval(hit, hit.wi, wo);
            if (!f.is_black()) {
                const ShadowConnection c =
                    connect_to_light(scene, hit, light, path.medium, sampler);
                if (!c.blocked()) {
                    const float w =
                        light.delta ? 1.f : power_heuristic(light.pdf, bsdf.pdf(hit, hit.wi, wo));
                    path.clock.record(path.throughput(f * light.weight * c.transmittance * w),
                                      *light.emitter, sampler, c.optical_length);
                }
            }
        }
        path.aim_at(light);
    }

    // Samples the BSDF for the next direction, then Russian roulette. Returns false when the
    // path ends.
    bool continue_from_surface(Sampler& sampler, PathState& path, const Hit& hit,
                               const Bsdf& bsdf) const {
        const float u_lobe = sampler.next_1d();
        const BsdfSample bs = bsdf.sample(hit, hit.wi, u_lobe, sampler.next_2d());
        if (!bs.valid() || bs.weight.is_black()) return false;
        path.throughput *= bs.weight;
        path.medium.refract(bs);
        path.prev_delta = (bs.sampled_lobe & kBsdfDelta) != 0;
        path.prev_pdf = bs.pdf;
        path.hit_share = 1.f;
        path.prev_p = hit.p;
        const Vec3 wo = hit.to_world(bs.wo);
        path.medium.cross(hit, wo);
        path.ray = hit.spawn(wo);
        const float survived = roulette(path.depth, path.throughput.max_gain(), sampler);
        if (survived == 0.f) return false;
        path.throughput *= Color(survived);
        ++path.depth;
        return true;
    }

    // ---- media -------------------------------------------------------------------------------

    // The path travels through a medium toward the surface `hit` (if `found`): a connection
    // strategy may place a vertex on the segment, and the distance strategy decides whether
    // the path scatters in the medium before reaching the surface.
    SegmentEnd medium_segment(const Scene& scene, Sampler& sampler, PathState& path, bool found,
                              const Hit& hit) const {
        const Medium& medium = *path.medium.medium;
        const DistanceMixture& strategy = path.distances(medium);
        const double u = path.next_u >= 0 ? path.next_u : double(sampler.next_1d());
        path.next_u = -1.0;
        const double tmax = found ? double(hit.t) : kInfinity;
        const bool may_scatter = !depth_exhausted(path.depth);
        ConnectionQuery cq;
        const bool connects = connecting_ && may_scatter &&
                              connection_vertex(scene, sampler, path, strategy, tmax, cq);
        const DistanceSample ds = sample_distance(medium, path.ray, tmax, strategy, u, sampler);
        path.throughput *= ds.weight;
        if (ds.scattered) {
            path.clock.travel_to(path.ray.at(float(ds.distance)), medium.eta());
            path.clock.reach_vertex();
            if (path.clock.expired() || path.throughput.is_black() || !may_scatter)
                return SegmentEnd::Stop;
            // This vertex's share of the segment's direct light (the rest is the connection
            // vertex's).
            float share = 1.f;
            if (connects) {
                const double pc = connection_->pdf(cq, ds.distance);
                share = mis_ ? float(balance_heuristic(ds.pdf, pc)) : (pc > 0 ? 0.f : 1.f);
            }
            return medium_vertex(scene, sampler, path, strategy, share) ? SegmentEnd::Scattered
                                                                        : SegmentEnd::Stop;
        }
        if (!found || path.throughput.is_black()) return SegmentEnd::Stop;
        return SegmentEnd::Surface;
    }

    // Connection strategy (ch. 5.6.2): an extra vertex on the segment, connected to the light
    // point the path aims at. It takes the segment's light connections over, or shares them
    // by MIS. Returns whether the strategy could place vertices on this segment (`cq` then
    // describes it).
    bool connection_vertex(const Scene& scene, Sampler& sampler, PathState& path,
                           const DistanceMixture& strategy, double tmax,
                           ConnectionQuery& cq) const {
        if (!path.has_target) {  // a path that has not sampled a light yet draws one to aim at
            const Vec2 u = sampler.next_2d();
            path.aim_at(scene.sample_emitter(path.ray.o, sampler.next_1d(), u));
        }
        const Medium& medium = *path.medium.medium;
        bool connects = false;
        if (path.has_target) {
            const double reach = connection_reach(path.ray.o, path.ray.d, path.target, medium.eta(),
                                                  path.clock.remaining());
            cq = ConnectionQuery{path.ray.o, path.ray.d, std::min(tmax, reach), path.target};
            connects = cq.length > 0;
        }
        const double r = connects ? connection_->sample(cq, sampler.next_1d()) : -1.0;
        const double pc = r >= 0 ? connection_->pdf(cq, r) : 0.0;
        if (pc > 0) {
            const float share = mis_ ? float(balance_heuristic(pc, strategy.pdf(r))) : 1.f;
            const Vec3 x = path.ray.o + path.ray.d * float(r);
            const Color w =
                medium.transmittance(path.ray, r, sampler) * medium.sigma_s(x) * float(1.0 / pc);
            PathClock at_x = path.clock;
            at_x.travel_to(x, medium.eta());
            medium_light(scene, sampler, path, at_x, x, -path.ray.d, w, true, share);
        }
        return connects;
    }

    // The vertex in the medium the clock just reached: a light sample (weighted by `share`),
    // then the direction out by the angular strategy. Returns false when the path ends.
    bool medium_vertex(const Scene& scene, Sampler& sampler, PathState& path,
                       const DistanceMixture& strategy, float share) const {
        const Vec3 p = path.clock.position(), wi = -path.ray.d;
        // Time angular sampling needs the next distance before the direction.
        double next_distance = kInfinity;
        if (!steady_angular_) {
            path.next_u = double(sampler.next_1d());
            next_distance = strategy.sample(path.next_u);
        }
        path.aim_at(medium_light(scene, sampler, path, path.clock, p, wi, Color(1.f),
                                 !steady_angular_, share));
        const PhaseFunction& phase = path.medium.medium->phase();
        Vec3 wo;
        if (steady_angular_) {
            wo = phase.sample(wi, sampler.next_2d());
            path.prev_pdf = phase.eval(wi, wo);
            path.hit_share = share;
        } else if (!angular_direction(sampler, path, p, wi, phase, next_distance, wo)) {
            return false;
        }
        path.prev_delta = false;
        path.prev_p = p;
        path.ray = Ray{p, wo, 0.f, kInfinity};
        ++path.depth;
        return true;
    }

    // Time angular sampling (ch. 5.6.3), alone or mixed half-half with the phase function. Its
    // direction density depends on the next distance, which an emitter hit would condition
    // on, so light sampling alone covers direct light at such vertices (hit_share 0).
    bool angular_direction(Sampler& sampler, PathState& path, const Vec3& p, const Vec3& wi,
                           const PhaseFunction& phase, double next_distance, Vec3& wo) const {
        const AngularQuery aq{p, wi, &phase, next_distance, path.has_target, path.target};
        const AngularMixture::Sample as = AngularMixture(*angular_, mis_).sample(aq, sampler);
        wo = as.wo;
        const double density = as.pdf;
        if (!(density > 0) || !std::isfinite(density)) return false;
        path.throughput *= Color(float(as.phase / density));
        path.prev_pdf = float(density);
        path.hit_share = 0.f;
        return true;
    }

    // Next-event estimation from medium point x, reached at `clock`'s time with `scale` on top
    // of the path's throughput: one light sample and its shadow connection through media,
    // weighted by `share` and, unless `light_only`, by MIS against phase sampling. Returns the
    // light sample.
    EmitterSample medium_light(const Scene& scene, Sampler& sampler, const PathState& path,
                               const PathClock& clock, const Vec3& x, const Vec3& wi,
                               const Color& scale, bool light_only, float share) const {
        const EmitterSample light = sample_emitter(scene, x, sampler);
        if (!(light.pdf > 0) || light.weight.is_black() || !(share > 0)) return light;
        const float f = path.medium.medium->phase().eval(wi, light.wi);
        if (!(f > 0)) return light;
        const ShadowConnection c = connect_to_light(scene, x, light, path.medium, sampler);
        if (c.blocked()) return light;
        const float w = light.delta || light_only ? 1.f : power_heuristic(light.pdf, f);
        clock.record(path.throughput(scale * light.weight * c.transmittance * (f * w * share)),
                     *light.emitter, sampler, c.optical_length);
        return light;
    }

    std::shared_ptr<DistanceSampler> distance_;
    std::shared_ptr<ConnectionSampler> connection_;
    std::shared_ptr<AngularSampler> angular_;
    bool mis_ = false;
    bool connecting_ = false;     // a connection strategy that places vertices
    bool steady_angular_ = true;  // directions from the phase function alone
};

// The three plugins built from this file (plugins/integrators/path/CMakeLists.txt).
#ifdef FEMTO_TRANSIENT_PATH
class TransientPath final : public PathIntegrator {
public:
    explicit TransientPath(const Properties& props) : PathIntegrator(props, 0) {}
};
#elif defined(FEMTO_VOLPATH)
class VolPath final : public PathIntegrator {
public:
    explicit VolPath(const Properties& props) : PathIntegrator(props, 5) {}
};
#else
class Path final : public PathIntegrator {
public:
    explicit Path(const Properties& props) : PathIntegrator(props, 5) {}
};
#endif

}  // namespace

#define FEMTO_PATH_STRATEGY_PARAMS                                                                 \
    {"distance", "distance", "mean_free_path",                                                     \
     "distance sampling in media (nested <distance>): mean_free_path or exponential"},             \
        {"connection", "connection", "deterministic",                                              \
         "light connections in media (nested <connection>): deterministic, line_to_point "         \
         "or equiangular"},                                                                        \
        {"angular", "angular", "phase",                                                            \
         "directions at medium vertices (nested <angular>): phase or time"},                       \
    {                                                                                              \
        "mis", "boolean", "false", "combine each time strategy with its steady counterpart by MIS" \
    }

#ifdef FEMTO_TRANSIENT_PATH
FEMTO_PLUGIN(TransientPath, femto::PluginKind::Integrator, "transient_path",
             "Transient path tracer: NEE + MIS, each contribution at its own time; the time "
             "window, not roulette, ends paths",
             {{"rr_depth", "integer", "0",
               "path depth at which Russian roulette starts; 0 = never (the window ends paths)"},
              FEMTO_PATH_STRATEGY_PARAMS})
#elif defined(FEMTO_VOLPATH)
FEMTO_PLUGIN(VolPath, femto::PluginKind::Integrator, "volpath",
             "Mitsuba's volumetric path tracer: femto's path, which renders media too (the same "
             "estimator and defaults)",
             {FEMTO_PATH_STRATEGY_PARAMS})
#else
FEMTO_PLUGIN(Path, femto::PluginKind::Integrator, "path",
             "Unidirectional path tracer with next-event estimation and MIS",
             {FEMTO_PATH_STRATEGY_PARAMS})
#endif
