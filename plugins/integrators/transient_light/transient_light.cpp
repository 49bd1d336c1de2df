// transient_light: light tracing (particle tracing), every vertex of a light path connected to
// the sensor and splatted onto the film at its own time (thesis ch. 5.4: the light subpaths of
// the transient path integral, eq. 5.11-5.16, seen by the camera).
//
// A light path starts on an emitter chosen uniformly (as light samples choose them), at the
// point and in the direction the emitter samples (Emitter::sample_emission()), at the time its
// pulse says. It then alternates, as the path tracer's camera paths do:
//   - medium_segment(): in a medium, a distance by mean-free-path sampling decides whether the
//     light scatters before the next surface (medium_vertex(): connection to the sensor, then a
//     direction by the phase function);
//   - surface_vertex(): null boundaries passed, the material's vertex event (delay, colour
//     transfer), a connection to the sensor (surface_to_sensor()), a BSDF sample to continue.
// The emitter's own point is connected too (emitter_seen(): the emitters the camera sees,
// unless hide_emitters), so a point light in view is a bright film point, which a path tracer
// never finds. Connections pass partly transparent surfaces (`mask`) weighted by their null
// transmission (trace_shadow()'s through_masks): light seen through a mask has no other way to
// the camera here.
//
// Normalisation: a render traces samples_per_pixel x pixels light paths; the sensor's
// importance (SensorSample::weight) and Film::add_splat_weight() make each pixel estimate what
// camera samples estimate, so this plugin and transient_path agree pixel by pixel.
//
// Time: LightClock (femto/path_clock.h) owns the rules; a splat's time is the light path's time
// plus the connection's optical length, which is also its sensor distance for world time.
// Light paths carry power, not importance, so BSDF weights use the adjoint shading-normal
// factor (adjoint_shading_factor()); femto's materials are otherwise symmetric (no 1/eta^2 on
// refraction, see the dielectric plugin).
#include <algorithm>
#include <cmath>

#include "femto/integrator.h"
#include "femto/path_clock.h"
#include "femto/plugin.h"
#include "femto/sensor.h"
#include "femto/transport.h"

namespace {

using namespace femto;

// Everything one light path carries from vertex to vertex.
struct LightPath {
    Ray ray;
    LightClock clock;
    MediumTracker medium;
    Color power;        // light the path carries (emitted / the densities that chose it)
    float start = 1.f;  // its largest channel at the emitter, for Russian roulette
    int64_t depth = 1;  // segments so far, the one being traced included
    // Mean-free-path distances, in the medium travelled last.
    DistanceMixtureCache distances{};
};

// What a segment through a medium ended in.
enum class SegmentEnd { Surface, Scattered, Stop };

class LightTracer final : public MonteCarloIntegrator {
public:
    explicit LightTracer(const Properties& props) : MonteCarloIntegrator(props, 0) {
        if (max_depth() == 0)
            props.fail("max_depth",
                       "transient_light needs max_depth >= 1 (or -1): a light path "
                       "needs at least its segment to the sensor");
    }

    SampleSource source() const override { return SampleSource::Light; }

    void preprocess(const Scene& scene) override {
        MonteCarloIntegrator::preprocess(scene);
        const Sensor& sensor = scene.sensor();
        if (!sensor.connectable())
            throw SceneError(sensor.location(),
                             "transient_light cannot splat onto a \"" + sensor.type_name() +
                                 "\" sensor: no light path can reach it by a connection (an "
                                 "orthographic camera's rays are parallel); use a perspective "
                                 "sensor or a camera-path integrator (transient_path)");
        starts_.prepare(scene, "transient_light");
        // Partly transparent surfaces (`mask`): connections to the sensor pass them weighted by
        // their null transmission, the only way this estimator sees light through them.
        through_masks_ = false;
        for (const auto& shape : scene.shapes())
            if (const auto& b = shape->bsdf(); b && (b->flags() & kBsdfNull) && !b->is_null())
                through_masks_ = true;
    }

    void sample_light(const Scene& scene, Sampler& sampler, SplatList& out) const override {
        const LightPathStarts::Start start = LightPathStarts::sample(scene, sampler);
        if (!start) return;
        const Emitter* emitter = start.emitter;
        const EmissionSample& es = start.emission;
        const float pmf = start.pmf;
        LightPath path{emission_ray(es), LightClock(scene, *emitter, es.p, sampler),
                       starts_.medium(*emitter, es, es.d), start.power()};
        path.start = path.power.max_component();
        if (path.clock.expired()) return;
        if (!hide_emitters()) emitter_seen(scene, sampler, path, *emitter, es, pmf, out);
        Hit hit;  // one for every vertex: intersect() sets all of it
        for (;;) {
            const bool found = scene.intersect(path.ray, hit);
            if (path.medium.medium) {
                const SegmentEnd end = medium_segment(scene, sampler, path, found, hit, out);
                if (end == SegmentEnd::Scattered) continue;
                if (end == SegmentEnd::Stop) return;
            }
            if (!found || !surface_vertex(scene, sampler, path, hit, out)) return;
        }
    }

private:
    // The emitter's point seen by the camera: emission toward the sensor over the connection.
    void emitter_seen(const Scene& scene, Sampler& sampler, const LightPath& path,
                      const Emitter& emitter, const EmissionSample& es, float pmf,
                      SplatList& out) const {
        const SensorSample ss = scene.sensor().sample_direct(es.p, sampler.next_2d());
        if (!ss.valid() || !path.clock.arrives_in_time(ss.distance)) return;
        const Color emitted = emitter.eval_direction(es, ss.wi);
        if (emitted.is_black()) return;
        const ShadowConnection c =
            connect_to_sensor(scene, es.p, ss, starts_.medium(emitter, es, ss.wi), sampler, es.n,
                              es.p_error, nullptr, through_masks_);
        if (c.blocked()) return;
        const float scale = ss.weight / (pmf * es.pdf_position);
        path.clock.record(out, ss.pos, emitted * c.transmittance * scale, c.optical_length);
    }

    // ---- surfaces ----------------------------------------------------------------------------

    // The light reaches surface `hit`. Returns false when the path ends there.
    bool surface_vertex(const Scene& scene, Sampler& sampler, LightPath& path, const Hit& hit,
                        SplatList& out) const {
        const Bsdf& bsdf = *hit.shape->bsdf();
        path.clock.travel_to(hit.p, path.medium.eta());
        if (path.clock.expired()) return false;
        if (bsdf.is_null()) {  // an index-matched boundary: not a scattering event
            path.medium.cross(hit, path.ray.d);
            path.ray = hit.spawn(path.ray.d);
            return true;
        }
        if (depth_exhausted(path.depth)) return false;  // no segment left for the sensor
        // The vertex's event (delay, colour transfer) applies to all light leaving it.
        const VertexEvent event = apply_vertex_event(bsdf, hit, sampler, path.clock);
        if (bsdf.flags() & kBsdfSmooth)
            surface_to_sensor(scene, sampler, path, hit, bsdf, event, out);
        return continue_from_surface(sampler, path, hit, bsdf, event);
    }

    // The connection from the surface vertex to the sensor.
    void surface_to_sensor(const Scene& scene, Sampler& sampler, const LightPath& path,
                           const Hit& hit, const Bsdf& bsdf, const VertexEvent& event,
                           SplatList& out) const {
        const SensorSample ss = scene.sensor().sample_direct(hit.p, sampler.next_2d());
        if (!ss.valid() || !path.clock.arrives_in_time(ss.distance)) return;
        const Color f = eval_adjoint(bsdf, hit, hit.wi, hit.to_local(ss.wi));
        if (f.is_black()) return;
        const float adjoint = adjoint_shading_factor(hit, -path.ray.d, ss.wi);
        if (!(adjoint > 0)) return;
        const ShadowConnection c =
            connect_to_sensor(scene, hit, ss, path.medium, sampler, nullptr, through_masks_);
        if (c.blocked()) return;
        const Color light = leaving(event, f * path.power) * c.transmittance;
        path.clock.record(out, ss.pos, light * (adjoint * ss.weight), c.optical_length);
    }

    // Samples the BSDF for the next direction, then Russian roulette. Returns false when the
    // path ends.
    bool continue_from_surface(Sampler& sampler, LightPath& path, const Hit& hit, const Bsdf& bsdf,
                               const VertexEvent& event) const {
        const float u_lobe = sampler.next_1d();
        const BsdfSample bs = sample_adjoint(bsdf, hit, hit.wi, u_lobe, sampler.next_2d());
        if (!bs.valid() || bs.weight.is_black()) return false;
        const Vec3 wo = hit.to_world(bs.wo);
        const float adjoint = adjoint_shading_factor(hit, -path.ray.d, wo);
        path.power = leaving(event, bs.weight * path.power) * adjoint;
        if (path.power.is_black()) return false;
        path.medium.refract(bs);
        path.medium.cross(hit, wo);
        path.ray = hit.spawn(wo);
        return survives(sampler, path);
    }

    // Russian roulette from rr_depth on, on the share of the emitted power the path still
    // carries; then the path has one more segment.
    bool survives(Sampler& sampler, LightPath& path) const {
        const float survived =
            roulette(path.depth, path.power.max_component() / path.start, sampler);
        if (survived == 0.f) return false;
        path.power *= survived;
        ++path.depth;
        return true;
    }

    // ---- media -------------------------------------------------------------------------------

    // The light travels through a medium toward surface `hit` (if `found`): a distance drawn
    // by mean-free-path sampling decides whether it scatters before reaching the surface.
    SegmentEnd medium_segment(const Scene& scene, Sampler& sampler, LightPath& path, bool found,
                              const Hit& hit, SplatList& out) const {
        const Medium& medium = *path.medium.medium;
        const DistanceMixture& strategy = path.distances(medium);
        const double tmax = found ? double(hit.t) : kInfinity;
        const double u = double(sampler.next_1d());
        const DistanceSample ds = sample_distance(medium, path.ray, tmax, strategy, u, sampler);
        path.power *= ds.weight;
        if (ds.scattered) {
            path.clock.travel_to(path.ray.at(float(ds.distance)), medium.eta());
            if (path.clock.expired() || path.power.is_black() || depth_exhausted(path.depth))
                return SegmentEnd::Stop;
            return medium_vertex(scene, sampler, path, out) ? SegmentEnd::Scattered
                                                            : SegmentEnd::Stop;
        }
        if (!found || path.power.is_black()) return SegmentEnd::Stop;
        return SegmentEnd::Surface;
    }

    // The medium vertex the clock just reached: a connection to the sensor, then the direction
    // out by the phase function (weight 1). Returns false when the path ends.
    bool medium_vertex(const Scene& scene, Sampler& sampler, LightPath& path,
                       SplatList& out) const {
        const Vec3 p = path.clock.position(), wi = -path.ray.d;
        const PhaseFunction& phase = path.medium.medium->phase();
        const SensorSample ss = scene.sensor().sample_direct(p, sampler.next_2d());
        if (ss.valid() && path.clock.arrives_in_time(ss.distance)) {
            const float f = phase.eval(wi, ss.wi);
            if (f > 0) {
                const ShadowConnection c = connect_to_sensor(scene, p, ss, path.medium, sampler,
                                                             Vec3(), 0.f, nullptr, through_masks_);
                if (!c.blocked())
                    path.clock.record(out, ss.pos, path.power * c.transmittance * (f * ss.weight),
                                      c.optical_length);
            }
        }
        path.ray = Ray{p, phase.sample(wi, sampler.next_2d()), 0.f, kInfinity};
        return survives(sampler, path);
    }

    LightPathStarts starts_;      // preprocess(): emitters checked, the media they sit in
    bool through_masks_ = false;  // preprocess(): a surface is partly transparent
};

}  // namespace

FEMTO_PLUGIN(LightTracer, femto::PluginKind::Integrator, "transient_light",
             "Transient light tracer: paths from the emitters, every vertex connected to the "
             "sensor and splatted at its own time",
             {{"rr_depth", "integer", "0",
               "path depth at which Russian roulette starts; 0 = never (the window ends paths)"}})
