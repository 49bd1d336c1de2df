#include "beam_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>

namespace femto_beams {

namespace {

// The query's context: Embree hands it to the filter, which records every hit and rejects it.
struct QueryContext {
    RTCIntersectContext context;  // first, so that Embree's pointer is the struct's
    std::vector<uint32_t>* found;
};

void record_hits(const RTCFilterFunctionNArguments* args) {
    auto* query = reinterpret_cast<const QueryContext*>(args->context);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        query->found->push_back(RTCHitN_primID(args->hit, args->N, i));
        args->valid[i] = 0;
    }
}

void check(RTCDevice device, const char* what) {
    const RTCError error = rtcGetDeviceError(device);
    if (error == RTC_ERROR_OUT_OF_MEMORY) throw std::bad_alloc();
    if (error != RTC_ERROR_NONE)
        throw std::runtime_error(std::string("transient_beams: Embree failed to ") + what +
                                 " (error " + std::to_string(int(error)) + ")");
}

}  // namespace

BeamMap::BeamMap() {
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw std::runtime_error("transient_beams: cannot create an Embree device");
}

BeamMap::~BeamMap() {
    release();
    rtcReleaseDevice(device_);
}

void BeamMap::release() {
    if (scene_) rtcReleaseScene(scene_);
    scene_ = nullptr;
}

void BeamMap::build(const std::vector<Vec3>& starts, const std::vector<Vec3>& ends, float radius) {
    release();
    radius_ = radius;
    scene_ = rtcNewScene(device_);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
    const size_t n = starts.size();
    if (n > 0) {
        RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE);
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 2 * n));
        auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, sizeof(unsigned), n));
        check(device_, "allocate the beams");
        // Each segment its own two vertices: index i + 1 never starts the next segment, so
        // Embree joins no two beams into one curve.
        for (size_t i = 0; i < n; ++i) {
            const Vec3* ends_of[2] = {&starts[i], &ends[i]};
            for (int k = 0; k < 2; ++k) {
                float* v = vertices + 4 * (2 * i + size_t(k));
                v[0] = ends_of[k]->x, v[1] = ends_of[k]->y, v[2] = ends_of[k]->z, v[3] = radius;
            }
            indices[i] = unsigned(2 * i);
        }
        rtcSetGeometryIntersectFilterFunction(geometry, record_hits);
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(scene_, geometry);
        rtcReleaseGeometry(geometry);
    }
    rtcCommitScene(scene_);
    check(device_, "build the beams' hierarchy");
}

void BeamMap::query(const Vec3& o, const Vec3& d, double length,
                    std::vector<uint32_t>& found) const {
    found.clear();
    if (!scene_) return;
    QueryContext query;
    rtcInitIntersectContext(&query.context);
    query.found = &found;
    // The ray starts 2R early and ends 2R late, so that capsules around its end points are
    // entered from outside (the caller keeps only closest points on [0, length]).
    const float back = 2.f * radius_;
    RTCRayHit rh;
    rh.ray.org_x = o.x - back * d.x;
    rh.ray.org_y = o.y - back * d.y;
    rh.ray.org_z = o.z - back * d.z;
    rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
    rh.ray.tnear = 0.f;
    rh.ray.tfar =
        std::isfinite(length) ? float(length) + 2.f * back : std::numeric_limits<float>::infinity();
    rh.ray.time = 0.f;
    rh.ray.mask = ~0u;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &query.context, &rh);
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
}

}  // namespace femto_beams
