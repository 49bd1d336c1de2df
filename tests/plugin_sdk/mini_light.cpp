// mini_light: a transient light tracer for scenes without media, written against the installed
// SDK: its samples start at the lights (SampleSource::Light), and every surface vertex of a
// light path is connected to the camera and splatted onto the film at its own time
// (docs/writing-plugins.md, "Splatting"). The host merges the splats in a fixed order and
// normalises them as camera samples, so it passes the conformance matrix like mini_path.
#include <femto/integrator.h>
#include <femto/path_clock.h>
#include <femto/plugin.h>
#include <femto/sensor.h>
#include <femto/transport.h>

namespace {

using namespace femto;

// A light path reaches the camera only through connections, so they pass partly transparent
// surfaces (`mask`), weighted by what those let through (c.transmittance); opaque ones block.
constexpr bool kThroughMasks = true;

class MiniLight final : public MonteCarloIntegrator {
public:
    explicit MiniLight(const Properties& props) : MonteCarloIntegrator(props, 0) {
        if (rr_depth() != 0) props.fail("rr_depth", "mini_light has no Russian roulette");
    }

    SampleSource source() const override { return SampleSource::Light; }

    void preprocess(const Scene& scene) override {
        MonteCarloIntegrator::preprocess(scene);
        if (scene.has_media()) throw SceneError("mini_light does not render media");
        if (!scene.sensor().connectable())
            throw SceneError(scene.sensor().location(), "mini_light needs a perspective sensor");
    }

    void sample_light(const Scene& scene, Sampler& sampler, SplatList& out) const override {
        float pmf = 0.f;
        const Emitter* emitter = scene.select_emitter(sampler.next_1d(), pmf);
        if (!emitter) return;
        const Vec2 u_position = sampler.next_2d();
        const EmissionSample es = emitter->sample_emission(u_position, sampler.next_2d());
        if (!es.valid()) return;
        LightClock clock(scene, *emitter, es.p, sampler);  // starts at the emission time
        MediumTracker index;                               // refractive index along the path
        // The emitter seen by the camera: its emission toward the sensor, one segment.
        if (const SensorSample ss = scene.sensor().sample_direct(es.p, sampler.next_2d());
            ss.valid() && !hide_emitters() && clock.arrives_in_time(ss.distance)) {
            const ShadowConnection c = connect_to_sensor(scene, es.p, ss, index, sampler, es.n,
                                                         es.p_error, nullptr, kThroughMasks);
            const float scale = ss.weight / (pmf * es.pdf_position);
            if (!c.blocked())
                clock.record(out, ss.pos,
                             emitter->eval_direction(es, ss.wi) * c.transmittance * scale,
                             c.optical_length);
        }
        Color power = es.weight / pmf;  // what the light path carries
        Ray ray = emission_ray(es);
        for (int64_t depth = 1;; ++depth) {
            Hit hit;
            if (!scene.intersect(ray, hit)) return;
            clock.travel_to(hit.p, index.eta());
            if (clock.expired()) return;
            const Bsdf& bsdf = *hit.shape->bsdf();
            if (bsdf.is_null()) {
                ray = hit.spawn(ray.d);
                --depth;
                continue;
            }
            if (depth_exhausted(depth)) return;  // the sensor needs one more segment
            // Fluorescence: a delay for the clock, a colour transfer for the light leaving.
            const VertexEvent event = apply_vertex_event(bsdf, hit, sampler, clock);
            // Connect to the camera: a splat at the film position the connection lands on.
            const SensorSample ss = scene.sensor().sample_direct(hit.p, sampler.next_2d());
            if (ss.valid() && (bsdf.flags() & kBsdfSmooth) && clock.arrives_in_time(ss.distance)) {
                const Color f = bsdf.eval(hit, hit.wi, hit.to_local(ss.wi)) *
                                adjoint_shading_factor(hit, -ray.d, ss.wi);
                const ShadowConnection c =
                    connect_to_sensor(scene, hit, ss, index, sampler, nullptr, kThroughMasks);
                if (!f.is_black() && !c.blocked())
                    clock.record(out, ss.pos,
                                 leaving(event, f * power) * c.transmittance * ss.weight,
                                 c.optical_length);
            }
            // Continue in a direction drawn from the BSDF.
            const float u = sampler.next_1d();
            const BsdfSample bs = bsdf.sample(hit, hit.wi, u, sampler.next_2d());
            if (!bs.valid() || bs.weight.is_black()) return;
            const Vec3 wo = hit.to_world(bs.wo);
            power = leaving(event, bs.weight * power) * adjoint_shading_factor(hit, -ray.d, wo);
            index.refract(bs);
            ray = hit.spawn(wo);
        }
    }
};

}  // namespace

FEMTO_PLUGIN(MiniLight, femto::PluginKind::Integrator, "mini_light",
             "A transient light tracer without media (example plugin built with the femto SDK)",
             {{"rr_depth", "integer", "0", "must stay 0: mini_light has no Russian roulette"}})
