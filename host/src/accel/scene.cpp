// The Scene: Embree 3 BVH over all shapes, ray queries, emitter selection.
#include "femto/scene.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <mutex>
#include <vector>

#include "accel/embree_scene.h"
#include "femto/error.h"
#include "femto/integrator.h"
#include "femto/medium.h"
#include "femto/sensor.h"
#include "scene/instancing.h"

namespace femto {

namespace {

struct alignas(64) RayCounter {
    uint64_t count = 0;
};

// Each scene's counters are per thread (tbb's thread-specific storage); a thread keeps a
// pointer to its counter of the scene it traced last, so that a ray costs an increment, not a
// thread-specific lookup (pthread_getspecific: ~1 % of a path tracer's instructions). Scenes
// are told apart by a serial number, never reused, unlike their addresses.
std::atomic<uint64_t> g_next_accel_serial{1};
struct LastRayCounter {
    uint64_t serial = 0;
    uint64_t* count = nullptr;
};
thread_local LastRayCounter t_last_ray_counter __attribute__((tls_model("initial-exec")));

}  // namespace

struct Scene::Accel {
    explicit Accel(const std::vector<std::shared_ptr<Shape>>& shapes) : embree(shapes) {}
    detail::EmbreeScene embree;
    tbb::enumerable_thread_specific<RayCounter, tbb::cache_aligned_allocator<RayCounter>,
                                    tbb::ets_key_per_instance>
        rays;
    const uint64_t serial = g_next_accel_serial.fetch_add(1);

    void count_ray() {
        LastRayCounter& last = t_last_ray_counter;
        if (last.serial != serial) last = {serial, &rays.local().count};
        ++*last.count;
    }
};

Scene::Scene(std::shared_ptr<Integrator> integrator, std::shared_ptr<Sensor> sensor,
             std::vector<std::shared_ptr<Shape>> shapes,
             std::vector<std::shared_ptr<Emitter>> emitters)
    : integrator_(std::move(integrator)),
      sensor_(std::move(sensor)),
      shapes_(std::move(shapes)),
      emitters_(std::move(emitters)) {
    for (const auto& s : shapes_)
        if (auto e = s->emitter_ptr()) {
            e->set_shape(s.get());
            emitters_.push_back(e);
        }
    for (const auto& e : emitters_) emitter_list_.push_back(e.get());
    for (const auto& s : shapes_)
        if (s->sensor_ptr() == sensor_) sensor_->attach(*s);
    if (!emitter_list_.empty()) {
        earliest_emission_ = emitter_list_[0]->pulse().earliest();
        for (const Emitter* e : emitter_list_)
            earliest_emission_ = std::min(earliest_emission_, e->pulse().earliest());
    }
    refresh_time_window();

    accel_ = std::make_unique<Accel>(shapes_);
    bounds_ = accel_->embree.bounds();
    place_distant_emitters();
    check_media_precision();
}

namespace {

// How far from the origin the box reaches along any axis: what sets the spacing of float
// positions inside it.
float reach_of(const Bounds3& b) {
    if (!b.valid()) return 0.f;
    float r = 0.f;
    for (int i = 0; i < 3; ++i) r = std::max({r, std::abs(b.min[i]), std::abs(b.max[i])});
    return r;
}

// The world box of a shape that is not an instance.
Bounds3 bounds_of(const Shape& shape) {
    Bounds3 b;
    if (shape.is_cylinder()) return detail::cylinder_box(shape);
    if (shape.is_sphere()) {
        b.expand(shape.sphere_center() - Vec3(shape.sphere_radius()));
        b.expand(shape.sphere_center() + Vec3(shape.sphere_radius()));
        return b;
    }
    for (const Vec3& p : shape.mesh().positions) b.expand(p);
    return b;
}

}  // namespace

// A path in a medium moves by free flights of about 1 / sigma_t. When that is below the spacing
// of float positions where the medium lies, a flight rounds to no move at all, time stops
// advancing with it, and a path never ends (a medium of sigma_t 1e30 hung the render). Such a
// medium is refused at load; denser than this but still resolvable is merely slow. A medium
// inside a shape lies within the shape's box; one outside shapes, around the sensor or an
// emitter, anywhere in the scene.
void Scene::check_media_precision() {
    Bounds3 scene_box = bounds_;
    scene_box.expand(sensor_->to_world().point(Vec3(0.f)));
    const float scene_reach = reach_of(scene_box);
    std::map<const Medium*, float> reach;  // the farthest any of its places reaches
    const auto place = [&](const Medium* m, float r) {
        if (m) reach[m] = std::max(reach[m], r);
    };
    place(sensor_->medium(), scene_reach);
    for (const Emitter* e : emitter_list_) place(e->medium(), scene_reach);
    for (const auto& s : shapes_) {
        if (dynamic_cast<const detail::ShapeInstance*>(s.get())) {
            for (const Medium* m : detail::shape_media(*s)) place(m, scene_reach);
            continue;
        }
        place(s->exterior(), scene_reach);
        if (s->interior()) place(s->interior(), reach_of(bounds_of(*s)));  // (a mesh's walk)
    }
    has_media_ = !reach.empty();
    for (const auto& [m, r] : reach) {
        const float spacing = std::nextafter(r, kInfinity) - r;
        const float free_path = 1.f / m->majorant();  // inf for a medium of zero density
        if (free_path >= spacing) continue;
        throw SceneError(
            m->location(),
            fmt::format("\"{}\": its extinction reaches {:g} per scene unit, a mean free path of "
                        "{:g}: below the spacing of positions where it lies ({:g}, up to {:g} "
                        "scene units from the origin), so paths in it could not move. Lower "
                        "sigma_t, sigma_s + sigma_a or scale.",
                        m->type_name(), m->majorant(), free_path, spacing, r));
    }
}

// Distant emitters measure their light from a sphere around everything paths start from (the
// shapes and the sensor), a little larger so that their plane waves start clear of the
// geometry and shadow rays toward them test the whole way out.
void Scene::place_distant_emitters() {
    Bounds3 extent = bounds_;
    extent.expand(sensor_->to_world().point(Vec3(0.f)));
    sphere_.center = extent.center();
    const float scale = std::max({1.f, std::abs(sphere_.center.x), std::abs(sphere_.center.y),
                                  std::abs(sphere_.center.z), extent.radius()});
    sphere_.radius = extent.radius() * (1.f + 1e-3f) + 1e-4f * scale;
    for (const auto& e : emitters_)
        if (e->is_infinite()) {
            e->set_scene_sphere(sphere_);
            if (!e->is_delta()) environment_.push_back(e.get());
        }
}

Scene::~Scene() = default;

bool Scene::intersect(const Ray& ray, Hit& hit) const {
    accel_->count_ray();
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    detail::init_rayhit(rh, ray.o, ray.d, ray.tmin, ray.tmax);
    rtcIntersect1(accel_->embree.get(), &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    accel_->embree.fill_hit(ray, rh, hit);
    return true;
}

bool Scene::occluded(const Ray& ray) const {
    accel_->count_ray();
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r;
    detail::init_ray(r, ray.o, ray.d, ray.tmin, ray.tmax);
    rtcOccluded1(accel_->embree.get(), &ctx, &r);
    return r.tfar < 0;  // Embree sets tfar = -inf on a hit
}

EmitterSample Scene::sample_emitter(const Vec3& ref, float u_select, Vec2 u) const {
    const size_t n = emitter_list_.size();
    // (Through a 32-bit index: x86-64 converts a float to an unsigned 64-bit one by a branch.)
    const size_t i = n ? std::min(size_t(uint32_t(u_select * float(n))), n - 1) : 0;
    // One result object on every path, so the emitter makes it in the caller's memory. (A
    // `return {}` on the no-emitter path made GCC build it in a temporary and copy it out, and
    // the copy's wide loads of fields the emitter had just stored one by one waited for the
    // stores.)
    EmitterSample s = n ? emitter_list_[i]->sample_direct(ref, u) : EmitterSample{};
    if (n == 0) return s;
    s.emitter = emitter_list_[i];
    if (n > 1) {  // (a division costs a light sample's wait even by 1)
        s.pdf /= float(n);
        s.weight *= float(n);
    }
    return s;
}

const Emitter* Scene::select_emitter(float u, float& pmf) const {
    const size_t n = emitter_list_.size();
    pmf = n ? 1.f / float(n) : 0.f;
    return n ? emitter_list_[std::min(size_t(u * float(n)), n - 1)] : nullptr;
}

float Scene::select_emitter_pmf(const Emitter&) const {
    return emitter_list_.empty() ? 0.f : 1.f / float(emitter_list_.size());
}

float Scene::pdf_emitter(const Emitter& emitter, const Vec3& ref, const Hit& hit) const {
    const size_t n = emitter_list_.size();
    return n ? emitter.pdf_direct(ref, hit) / float(n) : 0.f;
}

float Scene::pdf_environment(const Emitter& emitter, const Vec3& wi) const {
    const size_t n = emitter_list_.size();
    return n ? emitter.pdf_environment(wi) / float(n) : 0.f;
}

uint64_t Scene::rays_traced() const {
    uint64_t total = 0;
    for (const auto& c : accel_->rays) total += c.count;
    return total;
}

void Scene::refresh_time_window() {
    // A density estimator's time kernel reaches back from past the film's end.
    const double reach = integrator_ ? integrator_->time_reach() : 0.0;
    time_window_.end = sensor_->film().max_time() + reach;
    time_window_.world_end = sensor_->film().max_world_time() + reach;
    time_window_.prune = sensor_->film().prunes_paths();
    time_window_.earliest_emission = earliest_emission_;
}

}  // namespace femto
