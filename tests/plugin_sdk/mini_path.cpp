// mini_path: a transient path tracer for scenes without media, written against the installed
// SDK from the transport toolkit, as docs/writing-plugins.md walks through it. It follows the
// time rules through PathClock, so it passes the conformance matrix (tests/plugin_sdk runs it).
#include <femto/integrator.h>
#include <femto/mis.h>
#include <femto/path_clock.h>
#include <femto/plugin.h>
#include <femto/transport.h>

#include <algorithm>

namespace {

using namespace femto;

class MiniPath final : public MonteCarloIntegrator {
public:
    // max_depth, rr_depth (default 0 here: the film's window ends paths) and hide_emitters,
    // declared by MonteCarloIntegrator; the schema below only changes rr_depth's default.
    explicit MiniPath(const Properties& props) : MonteCarloIntegrator(props, 0) {}

    void preprocess(const Scene& scene) override {
        MonteCarloIntegrator::preprocess(scene);
        if (scene.has_media()) throw SceneError("mini_path does not render media");
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& camera_ray,
                ContributionList& out) const override {
        PathClock clock(scene, out, camera_ray.o);  // time: optical length, delays, emission
        Throughput beta;                            // path weight, colour transfers included
        MediumTracker index;                        // refractive index (dielectrics change it)
        Ray ray = camera_ray;
        float bsdf_pdf = 0.f;  // density of the direction that led here (0: a delta, or camera)
        Vec3 from;
        for (int64_t depth = 1;; ++depth) {
            Hit hit;
            if (!scene.intersect(ray, hit)) {  // the environment (constant, envmap), by MIS
                if (!(depth == 1 && hide_emitters()))
                    record_environment(scene, sampler, clock, beta, ray.d, index.eta(), bsdf_pdf,
                                       !(bsdf_pdf > 0));
                return;
            }
            clock.travel_to(hit.p, index.eta());  // from the last vertex, not the ray origin
            const Bsdf& bsdf = *hit.shape->bsdf();
            if (!bsdf.is_null()) clock.reach_vertex();
            if (clock.expired()) return;
            // Emission the path hit, weighted against light sampling from the previous vertex.
            if (const Emitter* em = hit.shape->emitter(); em && !(depth == 1 && hide_emitters())) {
                const float w = bsdf_pdf > 0
                                    ? power_heuristic(bsdf_pdf, scene.pdf_emitter(*em, from, hit))
                                    : 1.f;
                clock.record(beta(em->eval(hit, -ray.d) * w), *em, sampler);
            }
            if (bsdf.is_null()) {  // pass through without scattering
                ray = hit.spawn(ray.d);
                --depth;
                continue;
            }
            if (depth_exhausted(depth)) return;
            apply_vertex_event(bsdf, hit, sampler, clock, beta);
            // Next-event estimation: the light arrives over the connection's optical length.
            if (bsdf.flags() & kBsdfSmooth) {
                const EmitterSample ls = sample_emitter(scene, hit.p, sampler);
                const Vec3 wo = hit.to_local(ls.wi);
                const Color f = ls.pdf > 0 ? bsdf.eval(hit, hit.wi, wo) : Color(0.f);
                if (!f.is_black()) {
                    const ShadowConnection c = connect_to_light(scene, hit, ls, index, sampler);
                    const float w =
                        ls.delta ? 1.f : power_heuristic(ls.pdf, bsdf.pdf(hit, hit.wi, wo));
                    if (!c.blocked())
                        clock.record(beta(f * ls.weight * c.transmittance * w), *ls.emitter,
                                     sampler, c.optical_length);
                }
            }
            // Continue in a direction drawn from the BSDF.
            const float u = sampler.next_1d();
            const BsdfSample bs = bsdf.sample(hit, hit.wi, u, sampler.next_2d());
            if (!bs.valid() || bs.weight.is_black()) return;
            beta *= bs.weight;
            index.refract(bs);
            bsdf_pdf = (bs.sampled_lobe & kBsdfDelta) ? 0.f : bs.pdf;
            from = hit.p;
            ray = hit.spawn(hit.to_world(bs.wo));
            if (rr_depth() > 0 && depth >= rr_depth()) {
                const float q = std::min(beta.max_gain(), 0.95f);
                if (!(sampler.next_1d() < q)) return;
                beta *= Color(1.f / q);
            }
        }
    }
};

}  // namespace

FEMTO_PLUGIN(MiniPath, femto::PluginKind::Integrator, "mini_path",
             "A transient path tracer without media (example plugin built with the femto SDK)",
             {{"rr_depth", "integer", "0", "depth at which Russian roulette starts; 0 = never"}})
