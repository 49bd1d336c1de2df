#include "femto/path_tracer.h"

#include <algorithm>

#include "femto/bsdf.h"
#include "femto/emitter.h"
#include "femto/sensor.h"

namespace femto {

namespace {
inline float power_heuristic(float a, float b) {
    const float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0 ? a2 / (a2 + b2) : 0.f;
}

inline bool is_diagonal(const ColorMatrix& m) {
    return m.m[0][1] == 0.f && m.m[0][2] == 0.f && m.m[1][0] == 0.f && m.m[1][2] == 0.f &&
           m.m[2][0] == 0.f && m.m[2][1] == 0.f;
}
}  // namespace

void trace_path(const Scene& scene, Sampler& sampler, const Ray& camera_ray, ContributionList& out,
                const PathTracerOptions& opt) {
    if (opt.max_depth == 0) return;
    // A path whose time is past this can no longer reach the film (ch. 5.6.1).
    const double max_length = scene.sensor().film().max_path_length() - scene.earliest_emission();
    Ray ray = camera_ray;
    Color throughput(1.f);
    // Camera-side weight = mix * diag(throughput); mix stays the identity (and unused) until
    // a vertex event moves energy between colour channels (fluorescence).
    ColorMatrix mix;
    bool mixing = false;
    auto weighted = [&](const Color& c) {
        return mixing ? mix * (throughput * c) : throughput * c;
    };
    double path_length = 0.0;  // optical length travelled so far, plus scattering delays
    double index = 1.0;        // refractive index where the ray travels (light is slower by it)
    float prev_pdf = 1.f;
    bool prev_delta = true;
    Vec3 prev_p = ray.o;
    for (int64_t depth = 1;;) {
        Hit hit;
        if (!scene.intersect(ray, hit)) break;
        if (depth == 1 && out.sensor_distance() < 0)
            out.set_sensor_distance(path_length + hit.t * index);
        path_length += double(hit.t) * index;
        if (path_length > max_length) break;

        if (const Emitter* em = hit.shape->emitter()) {
            const Color Le = em->eval(hit, -ray.d);
            if (!Le.is_black() && !(depth == 1 && opt.hide_emitters)) {
                float w = 1.f;
                if (!prev_delta) w = power_heuristic(prev_pdf, scene.pdf_emitter(*em, prev_p, hit));
                const double t_emit = em->pulse().is_delta()
                                          ? em->pulse().offset
                                          : em->pulse().sample(sampler.next_1d());
                out.add(weighted(Le * w), path_length + t_emit);
            }
        }
        const Bsdf& bsdf = *hit.shape->bsdf();
        if (bsdf.is_null()) {  // index-matched pass-through: not a scattering event
            ray = hit.spawn(ray.d);
            continue;
        }
        if (opt.max_depth >= 0 && depth >= opt.max_depth) break;

        // The vertex's event (delay, colour transfer) applies to everything leaving it.
        if (bsdf.has_vertex_event()) {
            const VertexEvent ev = bsdf.sample_vertex_event(hit, sampler.next_1d());
            path_length += ev.delay;
            if (ev.transfers) {
                const ColorMatrix& t = ev.transfer;
                if (is_diagonal(t)) {  // mix * diag(throughput) * diag(t): stay in the fast path
                    throughput *= Color(t.m[0][0], t.m[1][1], t.m[2][2]);
                } else {
                    mix = (mixing ? mix : ColorMatrix()).scale_columns(throughput) * t;
                    mixing = true;
                    throughput = Color(1.f);
                }
            }
        }

        // Next-event estimation: its contribution arrives at its own time.
        if (bsdf.flags() & kBsdfSmooth) {
            const float u_sel = sampler.next_1d();
            const EmitterSample es = scene.sample_emitter(hit.p, u_sel, sampler.next_2d());
            if (es.pdf > 0 && !es.weight.is_black()) {
                const Vec3 wo = hit.to_local(es.wi);
                const Color f = bsdf.eval(hit, hit.wi, wo);
                if (!f.is_black() && !scene.occluded(hit.spawn_to(es.p))) {
                    const float w =
                        es.delta ? 1.f : power_heuristic(es.pdf, bsdf.pdf(hit, hit.wi, wo));
                    const PulseProfile& pulse = es.emitter->pulse();
                    const double t_emit =
                        pulse.is_delta() ? pulse.offset : pulse.sample(sampler.next_1d());
                    out.add(weighted(f * es.weight * w),
                            path_length + double(es.distance) + t_emit);
                }
            }
        }

        const float u_lobe = sampler.next_1d();
        const BsdfSample bs = bsdf.sample(hit, hit.wi, u_lobe, sampler.next_2d());
        if (!bs.valid() || bs.weight.is_black()) break;
        throughput *= bs.weight;
        // Crossing into a dielectric: BsdfSample::eta is the index ratio across the surface.
        if (bs.sampled_lobe &
            (kBsdfDeltaTransmission | kBsdfGlossyTransmission | kBsdfDiffuseTransmission))
            index *= double(bs.eta);
        prev_delta = (bs.sampled_lobe & kBsdfDelta) != 0;
        prev_pdf = bs.pdf;
        prev_p = hit.p;
        ray = hit.spawn(hit.to_world(bs.wo));

        if (opt.rr_depth > 0 && depth >= opt.rr_depth) {
            const float q = std::min(
                mixing ? mix.scale_columns(throughput).max_row_sum() : throughput.max_component(),
                0.95f);
            if (!(sampler.next_1d() < q)) break;
            throughput *= 1.f / q;
        }
        ++depth;
    }
}

}  // namespace femto
