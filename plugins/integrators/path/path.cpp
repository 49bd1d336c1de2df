// Unidirectional path tracer with next-event estimation and multiple importance sampling
// (power heuristic), Mitsuba's `path`. Every contribution is reported with the optical path
// length of the path that carried it, so the same estimator feeds steady and transient films.
#include "femto/bsdf.h"
#include "femto/integrator.h"
#include "femto/plugin.h"

namespace {

using namespace femto;

inline float power_heuristic(float a, float b) {
    const float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0 ? a2 / (a2 + b2) : 0.f;
}

class PathTracer final : public Integrator {
public:
    explicit PathTracer(const Properties& props) {
        max_depth_ = props.get_int("max_depth", -1);
        rr_depth_ = props.get_int("rr_depth", 5);
        hide_emitters_ = props.get_bool("hide_emitters", false);
        if (max_depth_ < -1) props.fail("max_depth", "max_depth must be -1 (unbounded) or >= 0");
        if (rr_depth_ < 1) props.fail("rr_depth", "rr_depth must be >= 1");
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& camera_ray,
                ContributionList& out) const override {
        if (max_depth_ == 0) return;
        const double max_length = scene.sensor().film().max_path_length();
        Ray ray = camera_ray;
        Color throughput(1.f);
        double path_length = 0.0;
        float prev_pdf = 1.f;
        bool prev_delta = true;
        Vec3 prev_p = ray.o;
        for (int64_t depth = 1;;) {
            Hit hit;
            if (!scene.intersect(ray, hit)) break;
            path_length += hit.t;
            if (path_length > max_length) break;

            if (const Emitter* em = hit.shape->emitter()) {
                const Color Le = em->eval(hit, -ray.d);
                if (!Le.is_black() && !(depth == 1 && hide_emitters_)) {
                    float w = 1.f;
                    if (!prev_delta)
                        w = power_heuristic(prev_pdf, scene.pdf_emitter(*em, prev_p, hit));
                    out.add(throughput * Le * w, path_length);
                }
            }
            const Bsdf& bsdf = *hit.shape->bsdf();
            if (bsdf.is_null()) {  // pass through; not a scattering event
                ray = hit.spawn(ray.d);
                continue;
            }
            if (max_depth_ >= 0 && depth >= max_depth_) break;

            // Next-event estimation.
            if (bsdf.flags() & kBsdfSmooth) {
                const float u_sel = sampler.next_1d();
                const EmitterSample es = scene.sample_emitter(hit.p, u_sel, sampler.next_2d());
                if (es.pdf > 0 && !es.weight.is_black()) {
                    const Vec3 wo = hit.to_local(es.wi);
                    const Color f = bsdf.eval(hit, hit.wi, wo);
                    if (!f.is_black() && !scene.occluded(hit.spawn_to(es.p))) {
                        const float w =
                            es.delta ? 1.f : power_heuristic(es.pdf, bsdf.pdf(hit, hit.wi, wo));
                        out.add(throughput * f * es.weight * w, path_length + double(es.distance));
                    }
                }
            } else {
                sampler.next_1d();  // keep the sample dimensions aligned across vertices
                sampler.next_2d();
            }

            // Continue the path by sampling the BSDF.
            const float u_lobe = sampler.next_1d();
            const BsdfSample bs = bsdf.sample(hit, hit.wi, u_lobe, sampler.next_2d());
            if (!bs.valid() || bs.weight.is_black()) break;
            throughput *= bs.weight;
            prev_delta = (bs.sampled_lobe & kBsdfDelta) != 0;
            prev_pdf = bs.pdf;
            prev_p = hit.p;
            ray = hit.spawn(hit.to_world(bs.wo));

            if (depth >= rr_depth_) {
                const float q = std::min(throughput.max_component(), 0.95f);
                if (!(sampler.next_1d() < q)) break;
                throughput *= 1.f / q;
            }
            ++depth;
        }
    }

private:
    int64_t max_depth_, rr_depth_;
    bool hide_emitters_;
};

}  // namespace

FEMTO_PLUGIN(PathTracer, femto::PluginKind::Integrator, "path",
             "Unidirectional path tracer with next-event estimation and MIS",
             {{"max_depth", "integer", "-1",
               "longest path (1 = visible emitters only, 2 = direct light; -1 = unbounded)"},
              {"rr_depth", "integer", "5", "path depth at which Russian roulette starts"},
              {"hide_emitters", "boolean", "false", "hide directly visible emitters"}})
