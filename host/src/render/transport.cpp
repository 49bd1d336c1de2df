// The transport toolkit's out-of-line pieces (femto/transport.h).
#include "femto/transport.h"

#include <algorithm>
#include <cmath>

namespace femto {

void Throughput::transfer(const ColorMatrix& t) {
    const bool diagonal = t.m[0][1] == 0.f && t.m[0][2] == 0.f && t.m[1][0] == 0.f &&
                          t.m[1][2] == 0.f && t.m[2][0] == 0.f && t.m[2][1] == 0.f;
    if (diagonal) {  // mix * diag(colour) * diag(t): stay in the fast form
        colour_ *= Color(t.m[0][0], t.m[1][1], t.m[2][2]);
        return;
    }
    mix_ = (mixing_ ? mix_ : ColorMatrix()).scale_columns(colour_) * t;
    mixing_ = true;
    colour_ = Color(1.f);
}

namespace {
// How far light travels from `from` to the light sample: between the actual points, in double
// (the shadow ray starts off the surface and stops short of the light).
double light_distance(const Vec3& from, const EmitterSample& light) {
    return std::isfinite(light.distance) ? distance_between(from, light.p) : double(light.distance);
}
}  // namespace

ShadowConnection trace_shadow(const Scene& scene, Ray ray, const Vec3& from, const Vec3& to,
                              MediumTracker medium, Sampler& sampler, MediumPieces* pieces,
                              bool through_masks) {
    ShadowConnection c;
    Vec3 last = from;  // the latest actual point: lengths are measured between these
    Hit hit;           // one for every boundary: intersect() sets all of it
    for (int crossings = 0; crossings < 256; ++crossings) {
        const bool found = scene.intersect(ray, hit);
        const Vec3 next = found ? hit.p : to;
        const double length = distance_between(last, next);
        // Attenuation over the length light travels, not over the ray's: a shadow ray stops
        // short of its target (by 1e-4 of its length), which would leave exp(1e-4 sigma_t d)
        // too much light.
        const std::optional<Color> known =
            pieces ? pieces->piece(medium.medium, length) : std::nullopt;
        if (medium.medium)
            c.transmittance *= known ? *known : medium.medium->transmittance(ray, length, sampler);
        c.optical_length += length * medium.eta();
        last = next;
        if (!found) return c;
        if (const Bsdf& bsdf = *hit.shape->bsdf(); !bsdf.is_null()) {
            if (!through_masks) return {Color(0.f), 0.0};
            c.transmittance *= bsdf.null_transmission(hit);
        }
        if (c.blocked()) return {Color(0.f), 0.0};
        medium.cross(hit, ray.d);
        const float left = ray.tmax - hit.t;
        ray = hit.spawn(ray.d);
        ray.tmax = left;
    }
    return {Color(0.f), 0.0};  // pathological nesting: treat as blocked
}

ShadowConnection connect_to_light(const Scene& scene, const Hit& from, const EmitterSample& light,
                                  const MediumTracker& medium, Sampler& sampler,
                                  MediumPieces* pieces) {
    const Ray ray = from.spawn_to(light.p);
    if (!scene.has_media()) {
        if (scene.occluded(ray)) return {Color(0.f), 0.0};
        return {Color(1.f), light_distance(from.p, light)};
    }
    MediumTracker beyond = medium;
    beyond.medium = medium.beyond(from, light.wi);
    return trace_shadow(scene, ray, from.p, light.p, beyond, sampler, pieces);
}

ShadowConnection connect_to_light(const Scene& scene, const Vec3& x, const EmitterSample& light,
                                  const MediumTracker& medium, Sampler& sampler,
                                  MediumPieces* pieces) {
    const Ray ray{x, light.wi, 0.f, shadow_ray_length(light.distance, light.p)};
    return trace_shadow(scene, ray, x, light.p, medium, sampler, pieces);
}

MediumTracker medium_at(const Scene& scene, const Vec3& p) {
    MediumTracker medium = MediumTracker::at_sensor(scene);
    if (!scene.has_media()) return medium;
    const Vec3 o = scene.sensor().to_world().point(Vec3(0.f));
    const float dist = length(p - o);
    if (!(dist > 0)) return medium;
    Ray ray{o, (p - o) / dist, 0.f, dist};
    Hit hit;
    for (int crossings = 0; crossings < 256; ++crossings) {
        if (!scene.intersect(ray, hit)) break;
        medium.cross(hit, ray.d);
        const float left = ray.tmax - hit.t;
        ray = hit.spawn(ray.d);
        ray.tmax = left;
    }
    return medium;
}

MediumTracker medium_at_emission(const Emitter& emitter, const EmissionSample& es, const Vec3& d,
                                 const Medium* surrounding) {
    const Shape* shape = emitter.shape();
    if (shape && shape->has_media())
        return {dot(d, es.n) < 0 ? shape->interior() : shape->exterior(), 1.0};
    return {emitter.medium() ? emitter.medium() : surrounding, 1.0};
}

void LightPathStarts::prepare(const Scene& scene, const std::string& integrator) {
    emitters_.clear();
    for (const Emitter* emitter : scene.emitters()) {
        EmissionSample es;  // any valid sample: a plugin without sample_emission() has none
        for (const float u : {0.5f, 0.25f, 0.75f})
            if (es = emitter->sample_emission({u, u}, {u, 1.f - u}); es.valid()) break;
        if (!es.valid())
            throw SceneError(emitter->location(), integrator + " cannot start light paths on a \"" +
                                                      emitter->type_name() +
                                                      "\" emitter (it does not sample its "
                                                      "emission)");
        const Vec3 off = es.p_error > 0 ? offset_origin(es.p, es.n, es.d, es.p_error) : es.p;
        emitters_.push_back({emitter, medium_at(scene, off).medium, es.delta_direction});
    }
}

LightPathStarts::Start LightPathStarts::sample(const Scene& scene, Sampler& sampler) {
    float pmf = 0.f;
    const Emitter* emitter = scene.select_emitter(sampler.next_1d(), pmf);
    const Vec2 u_position = emitter ? sampler.next_2d() : Vec2();
    const Vec2 u_direction = emitter ? sampler.next_2d() : Vec2();
    // The emitter's sample made in place in the result (which the caller's memory holds), not
    // assigned from a temporary: the copy's wide loads of fields just stored one by one would
    // wait for the stores (as in Scene::sample_emitter).
    Start start{nullptr, pmf,
                emitter ? emitter->sample_emission(u_position, u_direction) : EmissionSample()};
    if (emitter && start.emission.valid() && !start.emission.weight.is_black())
        start.emitter = emitter;
    return start;
}

const LightPathStarts::Known* LightPathStarts::find(const Emitter& emitter) const {
    for (const Known& k : emitters_)
        if (k.emitter == &emitter) return &k;
    return nullptr;
}

MediumTracker LightPathStarts::medium(const Emitter& emitter, const EmissionSample& es,
                                      const Vec3& d) const {
    const Known* k = find(emitter);
    return medium_at_emission(emitter, es, d, k ? k->surrounding : nullptr);
}

bool LightPathStarts::delta_direction(const Emitter& emitter) const {
    const Known* k = find(emitter);
    return k && k->delta_direction;
}

ShadowConnection connect_to_sensor(const Scene& scene, const Hit& from, const SensorSample& sensor,
                                   const MediumTracker& medium, Sampler& sampler,
                                   MediumPieces* pieces, bool through_masks) {
    const Ray ray = from.spawn_to(sensor.p);
    if (!scene.has_media() && !through_masks) {
        if (scene.occluded(ray)) return {Color(0.f), 0.0};
        return {Color(1.f), distance_between(from.p, sensor.p)};
    }
    MediumTracker beyond = medium;
    beyond.medium = medium.beyond(from, sensor.wi);
    return trace_shadow(scene, ray, from.p, sensor.p, beyond, sampler, pieces, through_masks);
}

ShadowConnection connect_to_sensor(const Scene& scene, const Vec3& x, const SensorSample& sensor,
                                   const MediumTracker& medium, Sampler& sampler, const Vec3& n,
                                   float p_error, MediumPieces* pieces, bool through_masks) {
    Ray ray{x, sensor.wi, 0.f, shadow_ray_length(float(sensor.distance), sensor.p)};
    if (p_error > 0) {
        ray.o = offset_origin(x, n, sensor.wi, p_error);
        ray.tmax = shadow_ray_length(length(sensor.p - ray.o), sensor.p);
    }
    return trace_shadow(scene, ray, x, sensor.p, medium, sampler, pieces, through_masks);
}

namespace {
// The medium's transmittance over d, from the strategy's survival there where that is it (one
// exponential instead of two: DistanceMixture::transmittance()).
Color transmittance(const Medium& medium, const Ray& ray, double d, const DistanceMixture& strategy,
                    const DistanceMixture::AtDistance& at, Sampler& sampler) {
    const std::optional<Color> known = strategy.transmittance(at);
    return known ? *known : medium.transmittance(ray, d, sampler);
}
}  // namespace

DistanceSample sample_distance(const Medium& medium, const Ray& ray, double tmax,
                               const DistanceMixture& strategy, double u, Sampler& sampler) {
    DistanceSample ds;
    const double r = strategy.sample(u);
    if (r < tmax) {
        ds.scattered = true;
        ds.distance = r;
        ds.at = strategy.at(r);
        ds.pdf = ds.at.pdf;
        const Vec3 p = ray.o + ray.d * float(r);
        ds.weight = transmittance(medium, ray, r, strategy, ds.at, sampler) * medium.sigma_s(p) *
                    float(1.0 / ds.pdf);
    } else if (std::isfinite(tmax)) {
        ds.at = strategy.at(tmax);
        ds.weight = transmittance(medium, ray, tmax, strategy, ds.at, sampler) *
                    float(1.0 / ds.at.survival);
    } else {
        ds.weight = Color(0.f);  // an infinite medium with no surface ahead absorbs it all
    }
    return ds;
}

// eta r + |x(r) - target| grows with r; its root is the smaller root of
// (eta^2 - 1) r^2 - 2 (eta left - b) r + (left^2 - |l|^2) = 0, written without cancellation.
double connection_reach(const Vec3& o, const Vec3& d, const Vec3& target, double eta,
                        double remaining) {
    const double left = remaining;
    if (!std::isfinite(left)) return kInfinity;
    if (!(left > 0)) return 0.0;
    const double lx = double(target.x) - o.x, ly = double(target.y) - o.y,
                 lz = double(target.z) - o.z;
    const double l2 = lx * lx + ly * ly + lz * lz, b = lx * d.x + ly * d.y + lz * d.z;
    if (!(l2 < left * left)) return 0.0;
    const double a = eta * eta - 1, half_b = eta * left - b, c = left * left - l2;
    return c / (half_b + std::sqrt(std::max(half_b * half_b - a * c, 0.0)));
}

}  // namespace femto
