// Direct illumination with multiple importance sampling of emitters and the BSDF (Mitsuba's
// `direct`): `emitter_samples` light samples and `bsdf_samples` BSDF samples per camera ray,
// combined with the power heuristic.
#include "femto/bsdf.h"
#include "femto/error.h"
#include "femto/integrator.h"
#include "femto/plugin.h"
#include "femto/scene.h"

namespace {

using namespace femto;

class Direct final : public Integrator {
public:
    explicit Direct(const Properties& props) {
        const int64_t shading = props.get_int("shading_samples", 1);
        emitter_samples_ = props.get_int("emitter_samples", shading);
        bsdf_samples_ = props.get_int("bsdf_samples", shading);
        hide_emitters_ = props.get_bool("hide_emitters", false);
        if (emitter_samples_ < 0) props.fail("emitter_samples", "emitter_samples must be >= 0");
        if (bsdf_samples_ < 0) props.fail("bsdf_samples", "bsdf_samples must be >= 0");
        if (emitter_samples_ + bsdf_samples_ == 0)
            props.fail("emitter_samples", "emitter_samples and bsdf_samples cannot both be 0");
    }

    void preprocess(const Scene& scene) override {
        if (scene.has_media())
            throw SceneError(
                "the direct integrator does not render participating media; use path or "
                "transient_path for a scene with <medium>");
    }

    // Power heuristic for n_a samples of density a against n_b samples of density b.
    static float mis(float n_a, float a, float n_b, float b) {
        const float x = n_a * a, y = n_b * b;
        return x * x + y * y > 0 ? x * x / (x * x + y * y) : 0.f;
    }

    static double emission_time(const Emitter& em, Sampler& sampler) {
        return em.pulse().is_delta() ? em.pulse().offset : em.pulse().sample(sampler.next_1d());
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& ray,
                ContributionList& out) const override {
        Hit hit;
        Ray r = ray;
        double length0 = 0;
        for (int guard = 0; guard < 64; ++guard) {  // skip null (pass-through) surfaces
            if (!scene.intersect(r, hit)) return;
            length0 += hit.t;
            if (const Emitter* em = hit.shape->emitter(); em && !hide_emitters_)
                out.add(em->eval(hit, -r.d), length0 + emission_time(*em, sampler));
            if (!hit.shape->bsdf()->is_null()) {
                out.set_sensor_distance(length0);
                break;
            }
            r = hit.spawn(r.d);
            if (guard == 63) return;
        }
        const Bsdf& bsdf = *hit.shape->bsdf();
        const float ne = float(emitter_samples_), nb = float(bsdf_samples_);
        if (bsdf.flags() & kBsdfSmooth)
            for (int64_t i = 0; i < emitter_samples_; ++i) {
                const float u_sel = sampler.next_1d();
                const EmitterSample es = scene.sample_emitter(hit.p, u_sel, sampler.next_2d());
                if (!(es.pdf > 0) || es.weight.is_black()) continue;
                const Vec3 wo = hit.to_local(es.wi);
                const Color f = bsdf.eval(hit, hit.wi, wo);
                if (f.is_black() || scene.occluded(hit.spawn_to(es.p))) continue;
                const float w = es.delta ? 1.f : mis(ne, es.pdf, nb, bsdf.pdf(hit, hit.wi, wo));
                out.add(f * es.weight * (w / ne),
                        length0 + double(es.distance) + emission_time(*es.emitter, sampler));
            }
        for (int64_t i = 0; i < bsdf_samples_; ++i) {
            const float u_lobe = sampler.next_1d();
            const BsdfSample bs = bsdf.sample(hit, hit.wi, u_lobe, sampler.next_2d());
            if (!bs.valid() || bs.weight.is_black()) continue;
            Hit lit;
            const Ray next = hit.spawn(hit.to_world(bs.wo));
            if (!scene.intersect(next, lit)) continue;
            const Emitter* em = lit.shape->emitter();
            if (!em) continue;
            const Color Le = em->eval(lit, -next.d);
            if (Le.is_black()) continue;
            const bool delta = (bs.sampled_lobe & kBsdfDelta) != 0;
            const float w = delta ? 1.f : mis(nb, bs.pdf, ne, scene.pdf_emitter(*em, hit.p, lit));
            out.add(bs.weight * Le * (w / nb),
                    length0 + double(lit.t) + emission_time(*em, sampler));
        }
    }

private:
    int64_t emitter_samples_, bsdf_samples_;
    bool hide_emitters_;
};

}  // namespace

FEMTO_PLUGIN(Direct, femto::PluginKind::Integrator, "direct",
             "Direct illumination: emitter and BSDF sampling combined with MIS",
             {{"shading_samples", "integer", "1",
               "default for both emitter_samples and bsdf_samples"},
              {"emitter_samples", "integer", "1", "emitter samples per camera ray"},
              {"bsdf_samples", "integer", "1", "BSDF samples per camera ray"},
              {"hide_emitters", "boolean", "false", "hide directly visible emitters"}})
