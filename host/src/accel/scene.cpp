// The Scene: Embree 3 BVH over all shapes, ray queries, emitter selection.
#include "femto/scene.h"

#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>

#include <cstdio>
#include <cstring>
#include <mutex>
#include <stdexcept>

#include "femto/bsdf.h"
#include "femto/integrator.h"
#include "femto/medium.h"

namespace femto {

namespace {

void embree_error(void*, RTCError code, const char* message) {
    if (code == RTC_ERROR_NONE) return;
    std::fprintf(stderr, "embree error %d: %s\n", int(code), message ? message : "");
}

RTCDevice device() {
    static RTCDevice dev = [] {
        RTCDevice d = rtcNewDevice("verbose=0");
        if (!d) throw std::runtime_error("cannot create the Embree device");
        rtcSetDeviceErrorFunction(d, embree_error, nullptr);
        return d;
    }();
    return dev;
}

// Surfaces with a pure null material let shadow rays through.
void ignore_in_shadow_rays(const RTCFilterFunctionNArguments* args) {
    for (unsigned i = 0; i < args->N; ++i) args->valid[i] = 0;
}

struct alignas(64) RayCounter {
    uint64_t count = 0;
};

}  // namespace

struct Scene::Accel {
    RTCScene scene = nullptr;
    std::vector<const Shape*> by_geom_id;
    tbb::enumerable_thread_specific<RayCounter, tbb::cache_aligned_allocator<RayCounter>,
                                    tbb::ets_key_per_instance>
        rays;
    ~Accel() {
        if (scene) rtcReleaseScene(scene);
    }
};

Scene::Scene(std::shared_ptr<Integrator> integrator, std::shared_ptr<Sensor> sensor,
             std::vector<std::shared_ptr<Shape>> shapes,
             std::vector<std::shared_ptr<Emitter>> emitters)
    : accel_(std::make_unique<Accel>()),
      integrator_(std::move(integrator)),
      sensor_(std::move(sensor)),
      shapes_(std::move(shapes)),
      emitters_(std::move(emitters)) {
    for (const auto& s : shapes_)
        if (auto e = s->emitter_ptr()) {
            e->set_shape(s.get());
            emitters_.push_back(e);
        }
    for (const auto& e : emitters_) emitter_list_.push_back(e.get());
    has_media_ = sensor_->medium() != nullptr;
    for (const auto& s : shapes_) has_media_ = has_media_ || s->has_media();
    for (const Emitter* e : emitter_list_) has_media_ = has_media_ || e->medium() != nullptr;
    if (!emitter_list_.empty()) {
        earliest_emission_ = emitter_list_[0]->pulse().earliest();
        for (const Emitter* e : emitter_list_)
            earliest_emission_ = std::min(earliest_emission_, e->pulse().earliest());
    }
    refresh_time_window();

    RTCDevice dev = device();
    accel_->scene = rtcNewScene(dev);
    rtcSetSceneBuildQuality(accel_->scene, RTC_BUILD_QUALITY_MEDIUM);
    rtcSetSceneFlags(accel_->scene, RTC_SCENE_FLAG_ROBUST);
    accel_->by_geom_id.resize(shapes_.size(), nullptr);
    for (size_t i = 0; i < shapes_.size(); ++i) {
        const Shape& shape = *shapes_[i];
        const bool null_surface = shape.bsdf() && shape.bsdf()->is_null();
        if (null_surface && !shape.emitter() && !shape.has_media())
            continue;  // invisible: nothing to see, block or enter
        RTCGeometry geom;
        if (shape.is_sphere()) {
            geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_SPHERE_POINT);
            auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
                geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
            const Vec3 c = shape.sphere_center();
            v[0] = c.x, v[1] = c.y, v[2] = c.z, v[3] = shape.sphere_radius();
            bounds_.expand(c - Vec3(shape.sphere_radius()));
            bounds_.expand(c + Vec3(shape.sphere_radius()));
        } else {
            const TriangleMesh& m = shape.mesh();
            geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
            auto* v = static_cast<float*>(
                rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                        3 * sizeof(float), m.positions.size()));
            std::memcpy(v, m.positions.data(), m.positions.size() * sizeof(Vec3));
            auto* idx = static_cast<uint32_t*>(
                rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                        3 * sizeof(uint32_t), m.triangle_count()));
            std::memcpy(idx, m.indices.data(), m.indices.size() * sizeof(uint32_t));
            for (const Vec3& p : m.positions) bounds_.expand(p);
        }
        if (null_surface) rtcSetGeometryOccludedFilterFunction(geom, ignore_in_shadow_rays);
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(accel_->scene, geom, unsigned(i));
        rtcReleaseGeometry(geom);
        accel_->by_geom_id[i] = &shape;
    }
    rtcCommitScene(accel_->scene);
    if (rtcGetDeviceError(dev) != RTC_ERROR_NONE)
        throw std::runtime_error("Embree failed to build the scene (see the message above)");
}

Scene::~Scene() = default;

bool Scene::intersect(const Ray& ray, Hit& hit) const {
    ++accel_->rays.local().count;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray.org_x = ray.o.x, rh.ray.org_y = ray.o.y, rh.ray.org_z = ray.o.z;
    rh.ray.dir_x = ray.d.x, rh.ray.dir_y = ray.d.y, rh.ray.dir_z = ray.d.z;
    rh.ray.tnear = ray.tmin;
    rh.ray.tfar = ray.tmax;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.flags = 0;
    rh.ray.time = 0.f;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(accel_->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    accel_->by_geom_id[rh.hit.geomID]->fill_hit(ray, rh.ray.tfar, rh.hit.primID, rh.hit.u, rh.hit.v,
                                                hit);
    return true;
}

bool Scene::occluded(const Ray& ray) const {
    ++accel_->rays.local().count;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r;
    r.org_x = ray.o.x, r.org_y = ray.o.y, r.org_z = ray.o.z;
    r.dir_x = ray.d.x, r.dir_y = ray.d.y, r.dir_z = ray.d.z;
    r.tnear = ray.tmin;
    r.tfar = ray.tmax;
    r.mask = 0xFFFFFFFFu;
    r.flags = 0;
    r.time = 0.f;
    rtcOccluded1(accel_->scene, &ctx, &r);
    return r.tfar < 0;  // Embree sets tfar = -inf on a hit
}

EmitterSample Scene::sample_emitter(const Vec3& ref, float u_select, Vec2 u) const {
    const size_t n = emitter_list_.size();
    if (n == 0) return {};
    const size_t i = std::min(size_t(u_select * float(n)), n - 1);
    EmitterSample s = emitter_list_[i]->sample_direct(ref, u);
    s.emitter = emitter_list_[i];
    s.pdf /= float(n);
    s.weight *= float(n);
    return s;
}

float Scene::pdf_emitter(const Emitter& emitter, const Vec3& ref, const Hit& hit) const {
    const size_t n = emitter_list_.size();
    return n ? emitter.pdf_direct(ref, hit) / float(n) : 0.f;
}

uint64_t Scene::rays_traced() const {
    uint64_t total = 0;
    for (const auto& c : accel_->rays) total += c.count;
    return total;
}

void Scene::refresh_time_window() {
    time_window_.end = sensor_->film().max_path_length();
    time_window_.earliest_emission = earliest_emission_;
}

}  // namespace femto
