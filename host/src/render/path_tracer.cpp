#include "femto/path_tracer.h"

#include <algorithm>
#include <cmath>

#include "femto/bsdf.h"
#include "femto/emitter.h"
#include "femto/medium.h"
#include "femto/sensor.h"
#include "femto/time_sampling.h"

namespace femto {

namespace {
inline float power_heuristic(float a, float b) {
    const float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0 ? a2 / (a2 + b2) : 0.f;
}

// The medium a path travels in after crossing `shape` in world direction d: a shape that
// bounds no medium leaves it unchanged; otherwise the side d goes to decides (the geometric
// normal points to the exterior).
inline const Medium* medium_after(const Hit& hit, const Vec3& d, const Medium* current) {
    const Shape& shape = *hit.shape;
    if (!shape.has_media()) return current;
    return dot(d, hit.ng) < 0 ? shape.interior() : shape.exterior();
}

// A shadow connection through media: transmittance and optical length (eta-weighted) from
// ray.o to ray.o + ray.d * ray.tmax, passing null surfaces (media boundaries) and changing
// media there; zero transmittance when an opaque surface blocks it. `index` is the
// refractive index outside media (as the path tracks it).
struct Connection {
    Color transmittance;
    double optical_length = 0.0;
};
Connection connect_through_media(const Scene& scene, Ray ray, const Medium* medium, double index,
                                 Sampler& sampler) {
    Connection c{Color(1.f), 0.0};
    for (int crossings = 0; crossings < 256; ++crossings) {
        Hit hit;
        const bool found = scene.intersect(ray, hit);
        const double segment = found ? double(hit.t) : double(ray.tmax);
        if (medium) {
            c.transmittance *= medium->transmittance(ray, segment, sampler);
            c.optical_length += segment * medium->eta();
        } else {
            c.optical_length += segment * index;
        }
        if (!found) return c;
        if (!hit.shape->bsdf()->is_null() || c.transmittance.is_black()) return {Color(0.f), 0.0};
        medium = medium_after(hit, ray.d, medium);
        const float left = ray.tmax - hit.t;
        ray = hit.spawn(ray.d);
        ray.tmax = left;
    }
    return {Color(0.f), 0.0};  // pathological nesting: treat as blocked
}

// Distance sampling in a medium (ch. 5.6.1): an exponential at the mean-free-path rate (the
// mean of sigma_t's channels, or the majorant of a heterogeneous medium), at a time-sampling
// strategy's rate, or a half-half mixture of both (one-sample MIS, balance heuristic). The
// weight is transmittance * sigma_s / pdf at a vertex, transmittance / P(pass) at a surface,
// so the estimator is unbiased for any rate (ratio-tracked transmittance when heterogeneous).
struct DistanceSample {
    bool scattered = false;
    double distance = 0.0;
    Color weight{1.f, 1.f, 1.f};
};
DistanceSample sample_distance(const Medium& medium, const Ray& ray, double tmax,
                               const PathTracerOptions& opt, const DistanceContext& ctx,
                               Sampler& sampler) {
    DistanceSample ds;
    const double steady = DistanceSampler::mean_free_path_rate(medium);
    const double strategy = opt.distance ? opt.distance->rate(medium, ctx) : steady;
    const bool mix = opt.distance_mis && opt.distance && strategy != steady;
    double u = double(sampler.next_1d());
    double rate = strategy;
    if (mix) {  // pick one of the two exponentials with probability 1/2, reusing u
        rate = u < 0.5 ? steady : strategy;
        u = u < 0.5 ? 2 * u : 2 * u - 1;
    }
    auto pdf = [&](double r) {
        return mix ? 0.5 * (DistanceSampler::pdf(steady, r) + DistanceSampler::pdf(strategy, r))
                   : DistanceSampler::pdf(rate, r);
    };
    auto survival = [&](double d) {
        return mix ? 0.5 * (DistanceSampler::survival(steady, d) +
                            DistanceSampler::survival(strategy, d))
                   : DistanceSampler::survival(rate, d);
    };
    const double r =
        rate > 0.0 ? DistanceSampler::sample(rate, std::min(u, 1.0 - 1e-12)) : kInfinity;
    if (r < tmax) {
        ds.scattered = true;
        ds.distance = r;
        const Vec3 p = ray.o + ray.d * float(r);
        ds.weight = medium.transmittance(ray, r, sampler) * medium.sigma_s(p) * float(1.0 / pdf(r));
    } else if (std::isfinite(tmax)) {
        ds.weight = medium.transmittance(ray, tmax, sampler) * float(1.0 / survival(tmax));
    } else {
        ds.weight = Color(0.f);  // an infinite medium with no surface ahead absorbs it all
    }
    return ds;
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
    const DistanceContext distance_ctx{scene.sensor().film().max_path_length()};
    const double max_length = distance_ctx.window_end - scene.earliest_emission();
    const bool media = scene.has_media();
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
    double index = 1.0;        // refractive index outside media (tracked through dielectrics)
    const Medium* medium = scene.sensor().medium();  // where the ray travels (null: none)
    auto speed_factor = [&] { return medium ? medium->eta() : index; };
    float prev_pdf = 1.f;
    bool prev_delta = true;
    Vec3 prev_p = ray.o;
    // Emission time of a sampled emitter's light.
    auto emission_time = [&](const Emitter& em) {
        return em.pulse().is_delta() ? em.pulse().offset : em.pulse().sample(sampler.next_1d());
    };
    for (int64_t depth = 1;;) {
        Hit hit;
        const bool found = scene.intersect(ray, hit);

        // In a medium the path may scatter before reaching the surface.
        if (medium) {
            const DistanceSample ds = sample_distance(
                *medium, ray, found ? double(hit.t) : kInfinity, opt, distance_ctx, sampler);
            throughput *= ds.weight;
            if (ds.scattered) {
                if (out.sensor_distance() < 0)
                    out.set_sensor_distance(path_length + ds.distance * medium->eta());
                path_length += ds.distance * medium->eta();
                if (path_length > max_length || throughput.is_black()) break;
                if (opt.max_depth >= 0 && depth >= opt.max_depth) break;
                const Vec3 p = ray.o + ray.d * float(ds.distance), wi = -ray.d;
                const PhaseFunction& phase = medium->phase();
                // Next-event estimation from the medium vertex.
                const float u_sel = sampler.next_1d();
                const EmitterSample es = scene.sample_emitter(p, u_sel, sampler.next_2d());
                if (es.pdf > 0 && !es.weight.is_black()) {
                    const float f = phase.eval(wi, es.wi);
                    if (f > 0) {
                        const Connection c = connect_through_media(
                            scene, Ray{p, es.wi, 0.f, es.distance * (1.f - 1e-4f)}, medium, index,
                            sampler);
                        if (!c.transmittance.is_black()) {
                            const float w = es.delta ? 1.f : power_heuristic(es.pdf, f);
                            out.add(weighted(es.weight * c.transmittance * (f * w)),
                                    path_length + c.optical_length + emission_time(*es.emitter));
                        }
                    }
                }
                const Vec3 wo = phase.sample(wi, sampler.next_2d());
                prev_pdf = phase.eval(wi, wo);
                prev_delta = false;
                prev_p = p;
                ray = Ray{p, wo, 0.f, kInfinity};
                ++depth;
                continue;
            }
            if (!found || throughput.is_black()) break;
        } else if (!found) {
            break;
        }

        if (depth == 1 && out.sensor_distance() < 0)
            out.set_sensor_distance(path_length + hit.t * speed_factor());
        path_length += double(hit.t) * speed_factor();
        if (path_length > max_length) break;

        if (const Emitter* em = hit.shape->emitter()) {
            const Color Le = em->eval(hit, -ray.d);
            if (!Le.is_black() && !(depth == 1 && opt.hide_emitters)) {
                float w = 1.f;
                if (!prev_delta) w = power_heuristic(prev_pdf, scene.pdf_emitter(*em, prev_p, hit));
                out.add(weighted(Le * w), path_length + emission_time(*em));
            }
        }
        const Bsdf& bsdf = *hit.shape->bsdf();
        if (bsdf.is_null()) {  // index-matched pass-through: not a scattering event
            if (media) medium = medium_after(hit, ray.d, medium);
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
                if (!f.is_black()) {
                    // Without media: an occlusion test, and light covers es.distance in vacuum.
                    Connection c{Color(1.f), double(es.distance)};
                    if (media)
                        c = connect_through_media(scene, hit.spawn_to(es.p),
                                                  medium_after(hit, es.wi, medium), index, sampler);
                    else if (scene.occluded(hit.spawn_to(es.p)))
                        c.transmittance = Color(0.f);
                    if (!c.transmittance.is_black()) {
                        const float w =
                            es.delta ? 1.f : power_heuristic(es.pdf, bsdf.pdf(hit, hit.wi, wo));
                        out.add(weighted(f * es.weight * c.transmittance * w),
                                path_length + c.optical_length + emission_time(*es.emitter));
                    }
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
        const Vec3 wo_world = hit.to_world(bs.wo);
        if (media) medium = medium_after(hit, wo_world, medium);
        ray = hit.spawn(wo_world);

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
