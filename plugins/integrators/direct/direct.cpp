// Direct illumination with multiple importance sampling of emitters and the BSDF (Mitsuba's
// `direct`): `emitter_samples` light samples and `bsdf_samples` BSDF samples per camera ray,
// combined with the power heuristic. Time follows the same rules as every integrator
// (PathClock): the first surface that scatters sets the sensor distance, its vertex event
// (a fluorescent material's delay and colour transfer) applies to all light leaving it.
#include <fmt/format.h>

#include "femto/bsdf.h"
#include "femto/error.h"
#include "femto/integrator.h"
#include "femto/mis.h"
#include "femto/path_clock.h"
#include "femto/plugin.h"
#include "femto/scene.h"
#include "femto/transport.h"

namespace {

using namespace femto;

class Direct final : public Integrator {
public:
    explicit Direct(const Properties& props) {
        // A camera sample's contributions (one per emitter or BSDF sample) stay in memory until
        // the film takes them: 2^16 of each is already far more than a render needs.
        constexpr int64_t kMaxSamples = int64_t(1) << 16;
        auto check = [&](const char* name, int64_t count) {
            if (count < 0 || count > kMaxSamples)
                props.fail(name,
                           fmt::format("{} must be in [0, {}], got {}", name, kMaxSamples, count));
        };
        const int64_t shading = props.get_int("shading_samples", 1);
        check("shading_samples", shading);  // first: the other two default to it
        emitter_samples_ = props.get_int("emitter_samples", shading);
        bsdf_samples_ = props.get_int("bsdf_samples", shading);
        hide_emitters_ = props.get_bool("hide_emitters", false);
        check("emitter_samples", emitter_samples_);
        check("bsdf_samples", bsdf_samples_);
        if (emitter_samples_ + bsdf_samples_ == 0)
            props.fail("emitter_samples", "emitter_samples and bsdf_samples cannot both be 0");
    }

    void preprocess(const Scene& scene) override {
        if (scene.has_media())
            throw SceneError(
                location(),
                "the direct integrator does not render participating media; use path or "
                "transient_path for a scene with <medium>");
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& ray,
                ContributionList& out) const override {
        PathClock clock(scene, out, ray.o);
        Throughput throughput;
        Hit hit;
        if (!first_vertex(scene, sampler, ray, clock, hit)) return;
        const Bsdf& bsdf = *hit.shape->bsdf();
        // The vertex's event (delay, colour transfer) applies to all light leaving it.
        apply_vertex_event(bsdf, hit, sampler, clock, throughput);
        const float ne = float(emitter_samples_), nb = float(bsdf_samples_);
        if (bsdf.flags() & kBsdfSmooth)
            for (int64_t i = 0; i < emitter_samples_; ++i) {
                const EmitterSample light = sample_emitter(scene, hit, sampler);
                if (!(light.pdf > 0) || light.weight.is_black()) continue;
                const Vec3 wo = hit.to_local(light.wi);
                const Color f = bsdf.eval(hit, hit.wi, wo);
                if (f.is_black()) continue;
                const ShadowConnection c = connect_to_light(scene, hit, light, {}, sampler);
                if (c.blocked()) continue;
                const float w = light.delta
                                    ? 1.f
                                    : power_heuristic(ne, light.pdf, nb, bsdf.pdf(hit, hit.wi, wo));
                clock.record(throughput(f * light.weight * (w / ne)), *light.emitter, sampler,
                             c.optical_length);
            }
        for (int64_t i = 0; i < bsdf_samples_; ++i) {
            const float u_lobe = sampler.next_1d();
            const BsdfSample bs = bsdf.sample(hit, hit.wi, u_lobe, sampler.next_2d());
            if (!bs.valid() || bs.weight.is_black()) continue;
            Hit lit;
            const Ray next = hit.spawn(hit.to_world(bs.wo));
            const bool delta = (bs.sampled_lobe & kBsdfDelta) != 0;
            if (!scene.intersect(next, lit)) {  // the environment, seen from the vertex
                for (const Emitter* env : scene.environment()) {
                    const float w = delta ? 1.f
                                          : power_heuristic(nb, bs.pdf, ne,
                                                            scene.pdf_environment(*env, next.d));
                    clock.record_distant(
                        throughput(bs.weight * env->eval_environment(next.d) * (w / nb)), *env,
                        sampler, next.d, 1.0);
                }
                continue;
            }
            const Emitter* em = lit.shape->emitter();
            if (!em) continue;
            const Color Le = em->eval(lit, -next.d);
            if (Le.is_black()) continue;
            const float w =
                delta ? 1.f : power_heuristic(nb, bs.pdf, ne, scene.pdf_emitter(*em, hit.p, lit));
            clock.record(throughput(bs.weight * Le * (w / nb)), *em, sampler,
                         distance_between(hit.p, lit.p));
        }
    }

private:
    // Follows the camera ray through null (pass-through) surfaces to the first surface that
    // scatters, recording the emitters seen on the way. Returns false when there is none.
    bool first_vertex(const Scene& scene, Sampler& sampler, const Ray& ray, PathClock& clock,
                      Hit& hit) const {
        Ray r = ray;
        for (int crossings = 0; crossings < 64; ++crossings) {
            if (!scene.intersect(r, hit)) {  // the camera sees the environment
                if (!hide_emitters_)
                    for (const Emitter* env : scene.environment())
                        clock.record_distant(env->eval_environment(r.d), *env, sampler, r.d, 1.0);
                return false;
            }
            clock.travel_to(hit.p, 1.0);
            const bool scatters = !hit.shape->bsdf()->is_null();
            if (scatters) clock.reach_vertex();
            if (const Emitter* em = hit.shape->emitter(); em && !hide_emitters_)
                clock.record(em->eval(hit, -r.d), *em, sampler);
            if (scatters) return true;
            r = hit.spawn(r.d);
        }
        return false;
    }

    int64_t emitter_samples_, bsdf_samples_;
    bool hide_emitters_;
};

}  // namespace

FEMTO_PLUGIN(Direct, femto::PluginKind::Integrator, "direct",
             "Direct illumination: emitter and BSDF sampling combined with MIS",
             {{"shading_samples", "integer", "1",
               "default for both emitter_samples and bsdf_samples (0 to 65536)"},
              {"emitter_samples", "integer", "1", "emitter samples per camera ray (0 to 65536)"},
              {"bsdf_samples", "integer", "1", "BSDF samples per camera ray (0 to 65536)"},
              {"hide_emitters", "boolean", "false", "hide directly visible emitters"}})
