// femto public API: shapes, surface hits and area sampling.
//
// A shape plugin only builds geometry in its constructor: a triangle mesh (set_mesh), an
// analytic sphere (set_sphere) or an analytic open cylinder (set_cylinder), already in world
// space. The host traces it with Embree and
// implements hit records and area/solid-angle sampling for both representations.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "femto/math.h"
#include "femto/object.h"
#include "femto/properties.h"
#include "femto/transform.h"

namespace femto {

class Bsdf;
class Emitter;
class Medium;
class Sensor;
class Shape;

/// What one pixel of a camera ray covers around a hit (valid = false for other rays, whose
/// other fields are then left as they were: read none of them unless valid):
/// the first-order change of the hit's quantities per pixel step on the film, from the ray's
/// differential (Ray::differential) intersected with the hit's tangent plane (pbrt's
/// SurfaceInteraction::ComputeDifferentials). Materials that prefilter their textures (the
/// BTF) use it to pick a level.
struct PixelFootprint {
    bool valid = false;
    Vec2 duv_dx, duv_dy;  ///< change of Hit::uv per pixel step in x and y
    /// From the hit's film position to its pixel's centre, in pixel steps (as duv_dx/duv_dy
    /// count them): the pixel's centre lies at uv + to_pixel_centre.x * duv_dx +
    /// to_pixel_centre.y * duv_dy (RayDifferential::to_pixel_centre).
    Vec2 to_pixel_centre{0.f, 0.f};
    Vec3 dp_dx, dp_dy;  ///< change of the position (world)
    Vec3 dn_dx, dn_dy;  ///< change of the shading normal (world)
    Vec3 dd_dx, dd_dy;  ///< change of the ray direction (world, unit directions)
    /// Half-angle (radians) of the light directions the current light sample stands for over
    /// the pixel: the emitter's own cone at p plus half the turn of its direction across the
    /// footprint. Set by sample_emitter(scene, Hit&, sampler) (femto/transport.h) before the
    /// material is evaluated toward the light; 0 until then.
    float light_cone = 0.f;
};

/// A ray-surface intersection, everything an integrator needs at a path vertex.
struct Hit {
    float t = kInfinity;  ///< ray distance
    Vec3 p;               ///< position
    Vec3 ng;              ///< geometric normal (unit; points to the shape's "outside")
    Frame sh;             ///< shading frame (sh.n is the interpolated normal)
    Vec2 uv;              ///< surface parameterization
    /// World-space derivative of the position with respect to uv.x (u), not normalized: the
    /// direction in which the texture's u grows, and by how much per unit u. Zero when the
    /// shape's parameterization is degenerate at this point (a sphere's poles, a triangle with
    /// degenerate uvs): materials then fall back to sh.s. Set for materials whose
    /// Bsdf::uses_tangent() is true and for rays with a differential; other hits may leave it
    /// zero (its solve on a triangle is not free).
    Vec3 dpdu;
    Vec3 wi;  ///< direction toward the ray origin, in the shading frame
    const Shape* shape = nullptr;
    uint32_t prim = 0;  ///< triangle index (0 for spheres and cylinders)
    /// How far rays leaving this hit start off the surface: kRayOffsetScale times the largest
    /// coordinate p was computed from (the triangle's vertices, or the sphere's centre plus
    /// radius), which bounds p's rounding and Embree's (docs/precision.md).
    float p_error = 0.f;
    /// The pixel footprint, filled by Scene::intersect() for rays that carry a differential
    /// (camera rays); invalid for every other hit.
    PixelFootprint footprint;

    Vec3 to_world(const Vec3& v) const { return sh.to_world(v); }
    Vec3 to_local(const Vec3& v) const { return sh.to_local(v); }
    /// A ray leaving this hit in world direction `d`, its origin offset by p_error against
    /// self-intersection. Measure path lengths from p, not from the ray's origin
    /// (PathClock::travel_to does).
    Ray spawn(const Vec3& d) const {
        return Ray{offset_origin(p, ng, d, p_error), d, 0.f, kInfinity};
    }
    /// A shadow ray from this hit toward point `target` (stops just short of it).
    Ray spawn_to(const Vec3& target) const;
};

/// A triangle mesh in world space. `normals` and `uvs` are per vertex and may be empty.
struct TriangleMesh {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;
    std::vector<Vec2> uvs;
    std::vector<uint32_t> indices;  ///< 3 per triangle
    size_t triangle_count() const { return indices.size() / 3; }
};

/// A point sampled on a shape for next-event estimation, seen from a reference point.
struct ShapeSample {
    Vec3 p, n;
    Vec2 uv;
    float pdf = 0.f;      ///< solid-angle density at the reference point (0 = failed)
    float p_error = 0.f;  ///< sample_area(): how far rays leaving p start off (Hit::p_error)
    /// sample_direct(): the unit direction from the reference point to p, and the distance
    /// (computed once here, so that an emitter need not take the same square root again).
    Vec3 wi;
    float distance = 0.f;
};

class Shape : public Object {
public:
    PluginKind kind() const override { return PluginKind::Shape; }
    ~Shape() override;

    bool is_sphere() const { return is_sphere_; }
    const TriangleMesh& mesh() const { return mesh_; }
    Vec3 sphere_center() const { return center_; }
    float sphere_radius() const { return radius_; }
    /// An analytic cylinder (set_cylinder): an open tube (no caps) of radius
    /// cylinder_radius() around the axis from cylinder_base() along cylinder_frame().n, of
    /// length cylinder_length(). As in Mitsuba, u = phi / 2pi with phi measured around the
    /// axis from frame.s toward frame.t, and v = z / length along the axis.
    bool is_cylinder() const { return is_cylinder_; }
    Vec3 cylinder_base() const { return center_; }
    const Frame& cylinder_frame() const { return cylinder_frame_; }
    float cylinder_radius() const { return radius_; }
    float cylinder_length() const { return length_; }
    /// The nearest intersection of `ray` with this cylinder in [ray.tmin, ray.tmax], solved in
    /// double precision (the host's Embree user geometry calls it); false on a miss.
    bool intersect_cylinder(const Ray& ray, float& t) const;
    bool flip_normals() const { return flip_normals_; }

    const Bsdf* bsdf() const { return bsdf_.get(); }
    /// Media on either side of the surface (`interior`: the side the normal points away
    /// from; nullptr = vacuum). A shape that names neither leaves the medium unchanged when a
    /// path crosses it.
    const Medium* interior() const { return interior_.get(); }
    const Medium* exterior() const { return exterior_.get(); }
    bool has_media() const { return interior_ || exterior_; }
    const Emitter* emitter() const { return emitter_.get(); }
    std::shared_ptr<Emitter> emitter_ptr() const { return emitter_; }
    /// A sensor nested in the shape (an irradiance meter measuring on it), or null.
    std::shared_ptr<Sensor> sensor_ptr() const { return sensor_; }
    /// The medium on the side the normal points to, shared (a sensor on the shape sits in it).
    std::shared_ptr<Medium> exterior_ptr() const { return exterior_; }
    float surface_area() const { return area_; }

    /// Fills `hit` for primitive `prim` hit at distance `t` with Embree's (u, v).
    void fill_hit(const Ray& ray, float t, uint32_t prim, float u, float v, Hit& hit) const;
    /// Samples a point for direct lighting of `ref` (solid-angle pdf; spheres sample the
    /// visible cone when `ref` is outside).
    ShapeSample sample_direct(const Vec3& ref, Vec2 u) const;
    /// Solid-angle pdf of sample_direct() choosing `hit` (a hit on this shape) from `ref`.
    float pdf_direct(const Vec3& ref, const Hit& hit) const;
    /// Half-angle (radians) of a cone from `ref` holding the whole shape: exact for a sphere,
    /// the cone around a bounding sphere otherwise; pi when `ref` is inside that sphere. What a
    /// prefiltering material needs of an area light's extent (thesis ch. 3's light solid angle).
    float subtended_half_angle(const Vec3& ref) const;
    /// Uniform point on the surface (area measure, pdf = 1/area).
    ShapeSample sample_area(Vec2 u) const;

    /// The parameters the constructor reads, for the plugin schemas.
    static std::vector<ParamSpec> inherited_params();

protected:
    /// Reads the parameters common to all shapes (`to_world`, `flip_normals`, the bsdf and
    /// emitter children, the `interior` / `exterior` media). A shape without a bsdf gets a
    /// diffuse one, as in Mitsuba.
    explicit Shape(const Properties& props);
    /// Sets the geometry; call exactly once from the plugin's constructor. Throws a located
    /// SceneError for empty or non-finite geometry.
    void set_mesh(TriangleMesh mesh);
    void set_sphere(const Vec3& center, float radius);
    /// `frame` is orthonormal (it may be left-handed, as a mirroring to_world makes it).
    void set_cylinder(const Vec3& base, const Frame& frame, float radius, float length);

    /// The shape's `to_world` (identity by default; never degenerate).
    Transform to_world_;

private:
    void finish_setup();
    // sample_area()'s body, which sample_direct() takes inline: through the exported call its
    // sample went to memory and back (defined in shape.cpp).
    ShapeSample area_sample(Vec2 u) const;
    SourceLocation location_;
    bool is_sphere_ = false;
    bool is_cylinder_ = false;
    bool flip_normals_ = false;
    bool fills_tangent_ = false;  // the bsdf reads Hit::dpdu (Bsdf::uses_tangent())
    bool flat_normals_ = false;   // each triangle's vertex normals are equal: no interpolation
    bool face_normals_ = false;   // ... and each is its triangle's face normal: Hit::ng too
    TriangleMesh mesh_;
    // Built on a mesh's first sample_area() (most shapes are never sampled): the triangles
    // by area, and each one's unit normal (flipped with the shape) and rounding bound.
    struct AreaSampling;
    const AreaSampling& area_sampling() const {
        // Double-checked: after the first build a sample pays one atomic load (std::call_once
        // would pay a thread-local lookup per call).
        if (const AreaSampling* built = area_sampling_.load(std::memory_order_acquire))
            return *built;
        return build_area_sampling();
    }
    const AreaSampling& build_area_sampling() const;
    mutable std::mutex area_sampling_mutex_;  // guards the build
    mutable std::unique_ptr<const AreaSampling> area_sampling_owner_;
    mutable std::atomic<const AreaSampling*> area_sampling_{nullptr};  // set once built
    Vec3 center_;
    float radius_ = 0.f;
    Frame cylinder_frame_;
    float length_ = 0.f;
    float area_ = 0.f;
    Vec3 bound_center_;  // a sphere holding the shape (subtended_half_angle())
    float bound_radius_ = 0.f;
    std::shared_ptr<Bsdf> bsdf_;
    std::shared_ptr<Emitter> emitter_;
    std::shared_ptr<Sensor> sensor_;
    std::shared_ptr<Medium> interior_, exterior_;
};

/// Moves a mesh read in object space to world space (what the obj and ply shapes share):
///  - positions through `to_world`; if it flips handedness (det < 0) the winding is reversed
///    so the geometric normal cross(p1-p0, p2-p0) keeps pointing to the side the transformed
///    normals point to (the outside, for a closed mesh wound as Mitsuba expects);
///  - file normals through the inverse transpose, normalized; a zero-length or non-finite one
///    counts as missing;
///  - missing normals: angle-weighted average of the adjacent face normals (Max 1999, as
///    Mitsuba 3), accumulated per file position `position_ids[v]` (of `position_count`) so
///    vertices split only by their uv stay smooth across the seam;
///  - `face_normals`: no vertex normals at all (flat shading from the geometric normal).
void mesh_to_world(TriangleMesh& mesh, const std::vector<uint32_t>& position_ids,
                   size_t position_count, const Transform& to_world, bool face_normals);
/// The same for a mesh whose vertices are all distinct file positions (ply, serialized).
void mesh_to_world(TriangleMesh& mesh, const Transform& to_world, bool face_normals);

/// Reads a `to_world` transform, rejecting degenerate (singular) ones with a located error.
Transform read_to_world(const Properties& props);

}  // namespace femto
