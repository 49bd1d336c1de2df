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

// The distance strategy in one medium (ch. 5.6.1): an exponential at the mean-free-path
// rate (the mean of sigma_t's channels, or the majorant of a heterogeneous medium), at a
// time-sampling strategy's rate, or a half-half mixture of both (one-sample MIS, balance
// heuristic). The rate does not depend on the direction, so a distance may be drawn before
// the direction it will be travelled in (time angular sampling needs that).
struct DistanceMixture {
    double steady = 0, strategy = 0;
    bool mix = false;
    DistanceMixture(const Medium& medium, const PathTracerOptions& opt, const DistanceContext& ctx)
        : steady(DistanceSampler::mean_free_path_rate(medium)),
          strategy(opt.distance ? opt.distance->rate(medium, ctx) : steady),
          mix(opt.mis && opt.distance && strategy != steady) {}
    double sample(double u) const {
        double rate = strategy;
        if (mix) {  // pick one of the two exponentials with probability 1/2, reusing u
            rate = u < 0.5 ? steady : strategy;
            u = u < 0.5 ? 2 * u : 2 * u - 1;
        }
        return rate > 0.0 ? DistanceSampler::sample(rate, std::min(u, 1.0 - 1e-12)) : kInfinity;
    }
    double pdf(double r) const {
        return mix ? 0.5 * (DistanceSampler::pdf(steady, r) + DistanceSampler::pdf(strategy, r))
                   : DistanceSampler::pdf(strategy, r);
    }
    double survival(double d) const {
        return mix ? 0.5 * (DistanceSampler::survival(steady, d) +
                            DistanceSampler::survival(strategy, d))
                   : DistanceSampler::survival(strategy, d);
    }
};

// A distance drawn from u along a ray: a medium vertex before tmax, or the surface at tmax.
// The weight is transmittance * sigma_s / pdf at a vertex, transmittance / P(pass) at a
// surface, so the estimator is unbiased for any rate (ratio-tracked transmittance when
// heterogeneous).
struct DistanceSample {
    bool scattered = false;
    double distance = 0.0;
    double pdf = 0.0;  // of the vertex, when scattered
    Color weight{1.f, 1.f, 1.f};
};
DistanceSample sample_distance(const Medium& medium, const Ray& ray, double tmax,
                               const DistanceMixture& strategy, double u, Sampler& sampler) {
    DistanceSample ds;
    const double r = strategy.sample(u);
    if (r < tmax) {
        ds.scattered = true;
        ds.distance = r;
        ds.pdf = strategy.pdf(r);
        const Vec3 p = ray.o + ray.d * float(r);
        ds.weight = medium.transmittance(ray, r, sampler) * medium.sigma_s(p) * float(1.0 / ds.pdf);
    } else if (std::isfinite(tmax)) {
        ds.weight = medium.transmittance(ray, tmax, sampler) * float(1.0 / strategy.survival(tmax));
    } else {
        ds.weight = Color(0.f);  // an infinite medium with no surface ahead absorbs it all
    }
    return ds;
}

// How far along a segment (origin o, unit direction d, in a medium of index eta) a vertex can
// lie and still connect to `target` within `left` of optical length: the connection covers
// eta * r in this medium, then at least |x(r) - target| (no medium is faster than vacuum).
// eta r + |x(r) - target| grows with r; its root is the smaller root of
// (eta^2 - 1) r^2 - 2 (eta left - b) r + (left^2 - |l|^2) = 0, written without cancellation.
// This only bounds where the connection strategy samples: the vertex's light sample may pick
// another light point, but wherever the strategy's density is zero the distance strategy's
// vertices keep the whole weight, so the estimate stays unbiased.
double connection_reach(const Vec3& o, const Vec3& d, const Vec3& target, double eta, double left) {
    if (!std::isfinite(left)) return kInfinity;
    if (!(left > 0)) return 0.0;
    const double lx = double(target.x) - o.x, ly = double(target.y) - o.y,
                 lz = double(target.z) - o.z;
    const double l2 = lx * lx + ly * ly + lz * lz, b = lx * d.x + ly * d.y + lz * d.z;
    if (!(l2 < left * left)) return 0.0;
    const double a = eta * eta - 1, half_b = eta * left - b, c = left * left - l2;
    return c / (half_b + std::sqrt(std::max(half_b * half_b - a * c, 0.0)));
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
    // Time-sampling strategies in media (ch. 5.6).
    const bool connecting = media && opt.connection && opt.connection->places_vertex();
    const bool steady_angular = !opt.angular || opt.angular->steady();
    // The connection and angular strategies aim at a light point: the latest one sampled
    // for next-event estimation (any point chosen before a segment's distances are drawn
    // keeps them unbiased).
    bool has_target = false;
    Vec3 target;
    auto set_target = [&](const EmitterSample& es) {
        if (es.pdf > 0 && std::isfinite(es.distance)) {
            target = es.p;
            has_target = true;
        }
    };
    double next_u = -1.0;   // the next distance's uniform, when drawn ahead (angular=time)
    float hit_share = 1.f;  // share of direct light that emitter hits from prev_p carry
    // Next-event estimation from a medium point x (the path arrives along -wi, `scale` on top
    // of the throughput, optical length `time` so far): one light sample and its shadow
    // connection through media, weighted by `share` and by MIS against phase sampling unless
    // `light_only`. Returns the light sample.
    auto medium_nee = [&](const Vec3& x, const Vec3& wi, const Color& scale, double time,
                          bool light_only, float share) {
        const float u_sel = sampler.next_1d();
        const EmitterSample es = scene.sample_emitter(x, u_sel, sampler.next_2d());
        if (!(es.pdf > 0) || es.weight.is_black() || !(share > 0)) return es;
        const float f = medium->phase().eval(wi, es.wi);
        if (!(f > 0)) return es;
        const Connection c = connect_through_media(
            scene, Ray{x, es.wi, 0.f, es.distance * (1.f - 1e-4f)}, medium, index, sampler);
        if (c.transmittance.is_black()) return es;
        const float w = es.delta || light_only ? 1.f : power_heuristic(es.pdf, f);
        out.add(weighted(scale * es.weight * c.transmittance * (f * w * share)),
                time + c.optical_length + emission_time(*es.emitter));
        return es;
    };
    for (int64_t depth = 1;;) {
        Hit hit;
        const bool found = scene.intersect(ray, hit);

        // In a medium the path may scatter before reaching the surface.
        if (medium) {
            const DistanceMixture strategy(*medium, opt, distance_ctx);
            const double u = next_u >= 0 ? next_u : double(sampler.next_1d());
            next_u = -1.0;
            const double tmax = found ? double(hit.t) : kInfinity;
            const bool may_scatter = !(opt.max_depth >= 0 && depth >= opt.max_depth);

            // Connection strategy (ch. 5.6.2): an extra vertex on this segment, connected to a
            // light; it takes the segment's light connections over, or shares them by MIS.
            ConnectionQuery cq;
            bool connects = false;
            if (connecting && may_scatter) {
                if (!has_target)
                    set_target(scene.sample_emitter(ray.o, sampler.next_1d(), sampler.next_2d()));
                if (has_target) {
                    const double reach = connection_reach(ray.o, ray.d, target, medium->eta(),
                                                          max_length - path_length);
                    cq = ConnectionQuery{ray.o, ray.d, std::min(tmax, reach), target};
                    connects = cq.length > 0;
                }
                const double r = connects ? opt.connection->sample(cq, sampler.next_1d()) : -1.0;
                const double pc = r >= 0 ? opt.connection->pdf(cq, r) : 0.0;
                if (pc > 0) {
                    const float share = opt.mis ? float(pc / (pc + strategy.pdf(r))) : 1.f;
                    const Vec3 x = ray.o + ray.d * float(r);
                    const Color w = medium->transmittance(ray, r, sampler) * medium->sigma_s(x) *
                                    float(1.0 / pc);
                    medium_nee(x, -ray.d, w, path_length + r * medium->eta(), true, share);
                }
            }

            const DistanceSample ds = sample_distance(*medium, ray, tmax, strategy, u, sampler);
            throughput *= ds.weight;
            if (ds.scattered) {
                if (out.sensor_distance() < 0)
                    out.set_sensor_distance(path_length + ds.distance * medium->eta());
                path_length += ds.distance * medium->eta();
                if (path_length > max_length || throughput.is_black()) break;
                if (!may_scatter) break;
                const Vec3 p = ray.o + ray.d * float(ds.distance), wi = -ray.d;
                const PhaseFunction& phase = medium->phase();
                // This vertex's share of the segment's direct light (the rest is the
                // connection vertex's).
                float share = 1.f;
                if (connects) {
                    const double pc = opt.connection->pdf(cq, ds.distance);
                    share = opt.mis ? float(ds.pdf / (ds.pdf + pc)) : (pc > 0 ? 0.f : 1.f);
                }
                // Time angular sampling needs the next distance before the direction.
                double next_distance = kInfinity;
                if (!steady_angular) {
                    next_u = double(sampler.next_1d());
                    next_distance = strategy.sample(next_u);
                }
                set_target(medium_nee(p, wi, Color(1.f), path_length, !steady_angular, share));
                Vec3 wo;
                if (steady_angular) {
                    wo = phase.sample(wi, sampler.next_2d());
                    prev_pdf = phase.eval(wi, wo);
                    hit_share = share;
                } else {
                    const AngularQuery aq{p, wi, &phase, next_distance, has_target, target};
                    const Vec2 u_dir = sampler.next_2d();
                    const bool use_phase = opt.mis && sampler.next_1d() < 0.5f;
                    wo = use_phase ? phase.sample(wi, u_dir) : opt.angular->sample(aq, u_dir);
                    const double f = double(phase.eval(wi, wo)), q = opt.angular->pdf(aq, wo);
                    const double density = opt.mis ? 0.5 * (f + q) : q;
                    if (!(density > 0) || !std::isfinite(density)) break;
                    throughput *= float(f / density);
                    prev_pdf = float(density);
                    // Its direction density depends on the next distance, which an emitter
                    // hit would condition on: light sampling alone covers direct light here.
                    hit_share = 0.f;
                }
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
                if (!prev_delta)
                    w = hit_share * power_heuristic(prev_pdf, scene.pdf_emitter(*em, prev_p, hit));
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
            set_target(es);
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
        hit_share = 1.f;
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
