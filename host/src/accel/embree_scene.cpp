// The Embree scene over a femto scene's shapes (see embree_scene.h).
#include "accel/embree_scene.h"

#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "femto/bsdf.h"

namespace femto::detail {

namespace {

void embree_error(void*, RTCError code, const char* message) {
    if (code == RTC_ERROR_NONE) return;
    std::fprintf(stderr, "embree error %d: %s\n", int(code), message ? message : "");
}

// Surfaces with a pure null material let shadow rays through.
void ignore_in_shadow_rays(const RTCFilterFunctionNArguments* args) {
    for (unsigned i = 0; i < args->N; ++i) args->valid[i] = 0;
}

}  // namespace

RTCDevice embree_device() {
    static RTCDevice dev = [] {
        RTCDevice d = rtcNewDevice("verbose=0");
        if (!d) throw std::runtime_error("cannot create the Embree device");
        rtcSetDeviceErrorFunction(d, embree_error, nullptr);
        return d;
    }();
    return dev;
}

EmbreeScene::EmbreeScene(const std::vector<std::shared_ptr<Shape>>& shapes, bool robust) {
    RTCDevice dev = embree_device();
    scene_ = rtcNewScene(dev);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
    rtcSetSceneFlags(scene_, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    by_geom_id_.resize(shapes.size(), nullptr);
    for (size_t i = 0; i < shapes.size(); ++i) {
        const Shape& shape = *shapes[i];
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
            ++spheres_;
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
            triangles_ += m.triangle_count();
        }
        if (null_surface) rtcSetGeometryOccludedFilterFunction(geom, ignore_in_shadow_rays);
        rtcCommitGeometry(geom);
        rtcAttachGeometryByID(scene_, geom, unsigned(i));
        rtcReleaseGeometry(geom);
        by_geom_id_[i] = &shape;
    }
    rtcCommitScene(scene_);
    if (rtcGetDeviceError(dev) != RTC_ERROR_NONE) {
        rtcReleaseScene(scene_);
        throw std::runtime_error("Embree failed to build the scene (see the message above)");
    }
}

EmbreeScene::~EmbreeScene() { rtcReleaseScene(scene_); }

}  // namespace femto::detail
