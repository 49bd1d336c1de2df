// Internal: the Embree scene over a femto scene's shapes. femto::Scene traces through it, and
// `femto bench`'s <raw_rays> (host/src/bench/raw_rays.cpp) builds one to measure Embree's raw
// ray rate in the same BVH, so the two share one construction (device, build quality, scene
// flags, geometry, null-surface filter).
#pragma once

#include <embree3/rtcore.h>

#include <cstddef>
#include <map>
#include <memory>
#include <vector>

#include "femto/math.h"
#include "femto/scene.h"
#include "femto/shape.h"

namespace femto::detail {

class ShapeGroup;
class ShapeInstance;

/// The process's Embree device, created on first use; Embree's errors go to stderr.
RTCDevice embree_device();

/// A committed Embree scene (RTC_BUILD_QUALITY_MEDIUM) holding one geometry per visible
/// shape, with geometry ID = the shape's index in `shapes`: world-space triangle meshes,
/// spheres as RTC_GEOMETRY_TYPE_SPHERE_POINT and cylinders as user geometry
/// (Shape::intersect_cylinder). An `instance` is an RTC_GEOMETRY_TYPE_INSTANCE of its
/// shapegroup's child scene, built once per group. A shape whose material is a pure `null` with no
/// emitter and no media is left out (nothing to see, block or enter); a `null` surface that is
/// kept lets shadow rays through (an occlusion filter).
class EmbreeScene {
public:
    /// `robust` sets RTC_SCENE_FLAG_ROBUST, as femto::Scene always does (false only for the
    /// ray benchmark's diagnostic). Throws std::runtime_error when Embree reports an error.
    explicit EmbreeScene(const std::vector<std::shared_ptr<Shape>>& shapes, bool robust = true);
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    RTCScene get() const { return scene_; }
    /// The hit record of an Embree hit of `ray` (in an instance: on the group's shape, moved to
    /// the world).
    void fill_hit(const Ray& ray, const RTCRayHit& rh, Hit& hit) const;
    /// The shape of each geometry ID; nullptr for shapes left out and for instances.
    const std::vector<const Shape*>& shapes() const { return by_geom_id_; }
    /// Bounds of the geometry in the scene.
    const Bounds3& bounds() const { return bounds_; }
    size_t triangles() const { return triangles_; }
    size_t spheres() const { return spheres_; }
    size_t cylinders() const { return cylinders_; }
    size_t instances() const { return instances_; }

private:
    struct Group {
        RTCScene scene = nullptr;
        std::vector<const Shape*> shapes;  // by geometry ID in `scene`
        Bounds3 bounds;                    // in the group's space
    };
    bool attach(RTCScene scene, const Shape& shape, unsigned id, Bounds3& bounds);
    const Group& group_scene(const ShapeGroup& group);
    void release();

    RTCScene scene_ = nullptr;
    bool robust_ = true;
    std::vector<const Shape*> by_geom_id_;
    struct Placed {  // an instance and its group's scene (std::map keeps it in place)
        const ShapeInstance* instance = nullptr;
        const Group* group = nullptr;
    };
    std::vector<Placed> instance_of_geom_id_;
    std::map<const ShapeGroup*, Group> groups_;
    Bounds3 bounds_;
    size_t triangles_ = 0, spheres_ = 0, cylinders_ = 0, instances_ = 0;
};

/// A box around an analytic cylinder (the shape's is_cylinder()).
Bounds3 cylinder_box(const Shape& shape);

/// An RTCRayHit for rtcIntersect1, every field Embree needs reset (tfar, mask, flags, geomID,
/// instID).
inline void init_rayhit(RTCRayHit& rh, const Vec3& o, const Vec3& d, float tmin, float tmax) {
    rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
    rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
    rh.ray.tnear = tmin;
    rh.ray.tfar = tmax;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.flags = 0;
    rh.ray.time = 0.f;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

/// An RTCRay for rtcOccluded1 (which sets tfar = -inf when something blocks it).
inline void init_ray(RTCRay& r, const Vec3& o, const Vec3& d, float tmin, float tmax) {
    r.org_x = o.x, r.org_y = o.y, r.org_z = o.z;
    r.dir_x = d.x, r.dir_y = d.y, r.dir_z = d.z;
    r.tnear = tmin;
    r.tfar = tmax;
    r.mask = 0xFFFFFFFFu;
    r.flags = 0;
    r.time = 0.f;
}

}  // namespace femto::detail
