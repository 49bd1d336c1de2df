#include "femto/shape.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "femto/bsdf.h"
#include "femto/emitter.h"
#include "femto/medium.h"
#include "femto/scene.h"
#include "femto/sensor.h"
#include "femto/warp.h"

namespace femto {

Ray Hit::spawn_to(const Vec3& target) const {
    const Vec3 d0 = target - p;
    const Vec3 o = offset_origin(p, ng, d0, p_error);
    const Vec3 d = target - o;
    const float dist = length(d);
    return Ray{o, d / dist, 0.f, shadow_ray_length(dist, target)};
}

namespace {
// Area of triangle i of `mesh`, in double (summed over a mesh of millions of triangles).
double triangle_area(const TriangleMesh& mesh, size_t i) {
    const Vec3& a = mesh.positions[mesh.indices[3 * i]];
    const Vec3& b = mesh.positions[mesh.indices[3 * i + 1]];
    const Vec3& c = mesh.positions[mesh.indices[3 * i + 2]];
    return 0.5 * double(length(cross(b - a, c - a)));
}

// Whether each triangle's three vertex normals are equal (a flat-shaded mesh's): its normal is
// then the same everywhere on it, and a hit need not interpolate and normalise them.
bool normals_constant_per_triangle(const TriangleMesh& mesh) {
    for (size_t i = 0; i < mesh.triangle_count(); ++i) {
        const uint32_t* idx = &mesh.indices[3 * i];
        const Vec3& n0 = mesh.normals[idx[0]];
        if (!(mesh.normals[idx[1]] == n0) || !(mesh.normals[idx[2]] == n0)) return false;
    }
    return true;
}

// Whether each triangle's (constant) vertex normal is its face normal on the side its winding
// gives, to within rounding (1e-6 apart: a millionth of a radian): then a hit's geometric
// normal can be that normal, without a normalisation per hit.
bool normals_are_face_normals(const TriangleMesh& mesh) {
    for (size_t i = 0; i < mesh.triangle_count(); ++i) {
        const uint32_t* idx = &mesh.indices[3 * i];
        const Vec3& p0 = mesh.positions[idx[0]];
        const Vec3 face = cross(mesh.positions[idx[1]] - p0, mesh.positions[idx[2]] - p0);
        const float l = length(face);
        if (!(l > 0) || !(squared_length(mesh.normals[idx[0]] - face / l) <= 1e-12f)) return false;
    }
    return true;
}
}  // namespace

std::vector<ParamSpec> Shape::inherited_params() {
    return inherit_params(
        Object::inherited_params(), "Shape",
        {{"to_world", "transform", "identity", "object-to-world transform"},
         {"flip_normals", "boolean", "false", "make the inside the outside"},
         {"bsdf", "bsdf", "diffuse", "material of the surface"},
         {"emitter", "emitter", "", "area emitter attached to the surface"},
         {"sensor", "sensor", "", "sensor measuring on the surface (irradiancemeter)"},
         {"interior", "medium", "", "medium inside the shape (nested or <ref name=\"interior\">)"},
         {"exterior", "medium", "", "medium outside the shape"}});
}

Shape::Shape(const Properties& props) : location_(props.location()) {
    to_world_ = read_to_world(props);
    flip_normals_ = props.get_bool("flip_normals", false);
    bsdf_ = std::static_pointer_cast<Bsdf>(props.child(PluginKind::Bsdf, "diffuse"));
    fills_tangent_ = bsdf_ && bsdf_->uses_tangent();
    interior_ = std::static_pointer_cast<Medium>(props.get_object("interior", PluginKind::Medium));
    exterior_ = std::static_pointer_cast<Medium>(props.get_object("exterior", PluginKind::Medium));
    for (const ObjectPtr& m : props.objects(PluginKind::Medium))
        if (m != interior_ && m != exterior_)
            throw SceneError(props.location(),
                             "a <medium> inside a shape must be named \"interior\" or "
                             "\"exterior\" (e.g. <ref name=\"interior\" id=\"fog\"/>)");
    emitter_ = std::static_pointer_cast<Emitter>(props.child(PluginKind::Emitter));
    if (emitter_) {
        if (emitter_->is_delta())
            throw SceneError(props.location(),
                             "only area emitters can be attached to a shape; put "
                             "point, spot and collimated emitters at the top level");
    }
    sensor_ = std::static_pointer_cast<Sensor>(props.child(PluginKind::Sensor));
}

Shape::~Shape() = default;

void Shape::set_mesh(TriangleMesh mesh) {
    if (mesh.indices.empty() || mesh.positions.empty())
        throw SceneError(location_, "the shape has no triangles");
    if (mesh.indices.size() % 3 != 0)
        throw SceneError(location_, "triangle index count is not a multiple of 3");
    for (uint32_t i : mesh.indices)
        if (i >= mesh.positions.size())
            throw SceneError(location_,
                             fmt::format("triangle index {} is out of range ({} vertices)", i,
                                         mesh.positions.size()));
    for (size_t i = 0; i < mesh.positions.size(); ++i)
        if (!within_scene_range(mesh.positions[i]))
            throw SceneError(location_, outside_scene_range(fmt::format("vertex {} (0-based) of "
                                                                        "the mesh, in the scene,",
                                                                        i),
                                                            mesh.positions[i]));
    if (!mesh.normals.empty()) {
        if (mesh.normals.size() != mesh.positions.size())
            throw SceneError(location_, "the mesh has a different number of normals and positions");
        for (Vec3& n : mesh.normals) {
            const float l = length(n);
            n = (l > 0 && std::isfinite(l)) ? n / l : Vec3(0, 0, 1);
        }
    }
    if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size())
        throw SceneError(location_, "the mesh has a different number of uvs and positions");
    flat_normals_ = !mesh.normals.empty() && normals_constant_per_triangle(mesh);
    face_normals_ = flat_normals_ && normals_are_face_normals(mesh);
    mesh_ = std::move(mesh);
    is_sphere_ = false;
    double area = 0;
    for (size_t i = 0; i < mesh_.triangle_count(); ++i) area += triangle_area(mesh_, i);
    area_ = float(area);
    if (!(area_ > 0)) throw SceneError(location_, "the mesh has zero surface area");
    Bounds3 box;
    for (const Vec3& q : mesh_.positions) box.expand(q);
    bound_center_ = box.center();
    bound_radius_ = 0.f;  // the farthest vertex: tighter than the box's half-diagonal
    for (const Vec3& q : mesh_.positions)
        bound_radius_ = std::max(bound_radius_, length(q - bound_center_));
}

void Shape::set_sphere(const Vec3& center, float radius) {
    if (!is_finite(center) || !(radius > 0) || !std::isfinite(radius))
        throw SceneError(location_,
                         fmt::format("a sphere needs a finite center and a positive radius "
                                     "(got {})",
                                     radius));
    if (!within_scene_range(center) || !(max_abs_component(center) + radius <= kMaxSceneCoordinate))
        throw SceneError(
            location_, outside_scene_range(fmt::format("a sphere of radius {:g}, centred where it "
                                                       "is,",
                                                       radius),
                                           center));
    is_sphere_ = true;
    center_ = center;
    radius_ = radius;
    area_ = 4.f * kPi * radius * radius;
    bound_center_ = center;
    bound_radius_ = radius;
}

void Shape::set_cylinder(const Vec3& base, const Frame& frame, float radius, float length) {
    if (!is_finite(base) || !is_finite(frame.s) || !is_finite(frame.t) || !is_finite(frame.n) ||
        !(radius > 0) || !std::isfinite(radius) || !(length > 0) || !std::isfinite(length))
        throw SceneError(location_,
                         fmt::format("a cylinder needs a finite axis, a positive radius and a "
                                     "positive length (got radius {}, length {})",
                                     radius, length));
    const Vec3 top = base + frame.n * length;
    if (!within_scene_range(base) || !within_scene_range(top) ||
        !(std::max(max_abs_component(base), max_abs_component(top)) + radius <=
          kMaxSceneCoordinate))
        throw SceneError(location_,
                         outside_scene_range(fmt::format("a cylinder of radius {:g}, from where "
                                                         "it starts,",
                                                         radius),
                                             base));
    is_sphere_ = false;
    is_cylinder_ = true;
    center_ = base;
    cylinder_frame_ = frame;
    radius_ = radius;
    length_ = length;
    area_ = float(2.0 * double(kPi) * double(radius) * double(length));
    bound_center_ = base + frame.n * (0.5f * length);
    bound_radius_ = std::hypot(radius, 0.5f * length);
}

float Shape::subtended_half_angle(const Vec3& ref) const {
    const float d = length(ref - bound_center_);
    if (!(d > bound_radius_)) return kPi;
    return std::asin(bound_radius_ / d);
}

bool Shape::intersect_cylinder(const Ray& ray, float& t_hit) const {
    // In the cylinder's frame (z along the axis from its base), in double precision:
    // |o_xy + t d_xy|^2 = r^2.
    const Frame& f = cylinder_frame_;
    const double rel[3] = {double(ray.o.x) - center_.x, double(ray.o.y) - center_.y,
                           double(ray.o.z) - center_.z};
    auto along = [](const double v[3], const Vec3& a) {
        return v[0] * a.x + v[1] * a.y + v[2] * a.z;
    };
    const double dv[3] = {ray.d.x, ray.d.y, ray.d.z};
    const double ox = along(rel, f.s), oy = along(rel, f.t), oz = along(rel, f.n);
    const double dx = along(dv, f.s), dy = along(dv, f.t), dz = along(dv, f.n);
    const double a = dx * dx + dy * dy;
    const double b = 2.0 * (dx * ox + dy * oy);
    const double r = radius_;
    const double c = (ox - r) * (ox + r) + oy * oy;
    const double disc = b * b - 4.0 * a * c;
    if (!(a > 0) || !(disc >= 0)) return false;  // parallel to the axis, or a miss
    const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
    double t0 = q / a, t1 = q != 0 ? c / q : t0;
    if (t0 > t1) std::swap(t0, t1);
    for (const double t : {t0, t1}) {
        const double z = oz + dz * t;
        if (t >= ray.tmin && t <= ray.tmax && z >= 0 && z <= length_) {
            t_hit = float(t);
            return true;
        }
    }
    return false;
}

namespace {

/// A hit on an analytic cylinder: the point projected onto the surface (as Mitsuba 0.6 does
/// against round-off), the outward radial normal, Mitsuba's (phi / 2pi, z / length) and the
/// derivative of the point along that u: 2pi r times the circle's tangent.
void fill_cylinder_hit(const Vec3& base, const Frame& f, float radius, float length, const Vec3& p,
                       Hit& hit, Vec3& normal) {
    const Vec3 rel = p - base;
    const float x = dot(rel, f.s), y = dot(rel, f.t), z = dot(rel, f.n);
    const float rho = std::sqrt(x * x + y * y);
    const float cx = rho > 0 ? x / rho : 1.f, cy = rho > 0 ? y / rho : 0.f;
    normal = normalize(f.s * cx + f.t * cy);
    hit.p = base + f.n * z + normal * radius;
    const float phi = std::atan2(cy, cx);
    hit.uv = {(phi < 0 ? phi + 2 * kPi : phi) * kInvTwoPi, clamp(z / length, 0.f, 1.f)};
    hit.dpdu = (f.t * cx - f.s * cy) * (2 * kPi * radius);
    hit.p_error =
        kRayOffsetScale *
        (std::max(max_abs_component(base), max_abs_component(base + f.n * length)) + radius);
}

/// dp/du and dp/dv on the triangle p0 p1 p2 with vertex uvs uv0 uv1 uv2: the solution of the
/// 2x2 system dp_i2 = duv_i2.x dpdu + duv_i2.y dpdv (i = 0, 1), as in pbrt. Zero when the uvs
/// do not span the plane: their determinant is tiny next to the product of the uv edges it is
/// made of (the sine of the angle between them is below 1e-5, under a float's rounding of
/// near-collinear uvs), or the result is not finite.
struct TriangleTangents {
    Vec3 dpdu, dpdv;
};
TriangleTangents triangle_tangents(const Vec3& p0, const Vec3& p1, const Vec3& p2, Vec2 uv0,
                                   Vec2 uv1, Vec2 uv2) {
    const Vec2 duv02 = uv0 - uv2, duv12 = uv1 - uv2;
    const float det = duv02.x * duv12.y - duv02.y * duv12.x;
    // (uv edges are far from float's overflow: no need for hypot's care, which costs a call)
    const float edges = std::sqrt((duv02.x * duv02.x + duv02.y * duv02.y) *
                                  (duv12.x * duv12.x + duv12.y * duv12.y));
    constexpr float kMinSine = 1e-5f;
    if (!(std::abs(det) > kMinSine * edges)) return {Vec3(0.f), Vec3(0.f)};
    const Vec3 dpdu = ((p0 - p2) * duv12.y - (p1 - p2) * duv02.y) / det;
    const Vec3 dpdv = ((p1 - p2) * duv02.x - (p0 - p2) * duv12.x) / det;
    return {is_finite(dpdu) ? dpdu : Vec3(0.f), is_finite(dpdv) ? dpdv : Vec3(0.f)};
}

// -- pixel footprints (Hit::footprint) --------------------------------------------------------

/// Where the line o + t d meets the plane through p with normal n; false when they are
/// parallel (or the intersection is not finite).
bool meet_tangent_plane(const Vec3& p, const Vec3& n, const Vec3& o, const Vec3& d, Vec3& out) {
    const float t = dot(n, p - o) / dot(n, d);
    if (!std::isfinite(t)) return false;
    out = o + d * t;
    return is_finite(out);
}

/// The coefficients (a, b) of the least-squares fit dp ~ a e1 + b e2 (the normal equations),
/// for a dp in the plane the two tangents span; zero when they do not span one.
Vec2 coordinates_in_tangents(const Vec3& dp, const Vec3& e1, const Vec3& e2) {
    const double a11 = dot(e1, e1), a12 = dot(e1, e2), a22 = dot(e2, e2);
    const double det = a11 * a22 - a12 * a12;
    if (!(det > 1e-12 * a11 * a22)) return Vec2{0.f, 0.f};  // parallel or zero tangents
    const double b1 = dot(e1, dp), b2 = dot(e2, dp);
    const Vec2 out{float((a22 * b1 - a12 * b2) / det), float((a11 * b2 - a12 * b1) / det)};
    return std::isfinite(out.x) && std::isfinite(out.y) ? out : Vec2{0.f, 0.f};
}

/// dp/dv at a hit (Hit::dpdu's partner, for the footprint's uv change).
Vec3 hit_dpdv(const Shape& shape, const Hit& hit) {
    if (shape.is_cylinder()) return shape.cylinder_frame().n * shape.cylinder_length();
    if (shape.is_sphere()) {
        // d/dv of center + r (sin theta cos phi, sin theta sin phi, cos theta), theta = pi v:
        // zero at the poles, as dpdu.
        const Vec3 local = (hit.p - shape.sphere_center()) / shape.sphere_radius();
        const float sin_theta = std::hypot(local.x, local.y);
        if (!(sin_theta > 0)) return Vec3(0.f);
        const float cos_over_sin = local.z / sin_theta;
        return Vec3(local.x * cos_over_sin, local.y * cos_over_sin, -sin_theta) *
               (kPi * shape.sphere_radius());
    }
    const TriangleMesh& m = shape.mesh();
    const uint32_t* idx = &m.indices[3 * hit.prim];
    const Vec3 &p0 = m.positions[idx[0]], &p1 = m.positions[idx[1]], &p2 = m.positions[idx[2]];
    if (m.uvs.empty()) return p2 - p0;  // uv are the barycentrics of p1 and p2
    return triangle_tangents(p0, p1, p2, m.uvs[idx[0]], m.uvs[idx[1]], m.uvs[idx[2]]).dpdv;
}

/// The change of the shading normal (unflipped) for a change dp of the hit on the surface.
/// `barycentrics` are the hit's (u, v) on a triangle.
Vec3 normal_change(const Shape& shape, const Hit& hit, Vec2 barycentrics, const Vec3& dp) {
    if (shape.is_sphere()) return dp / shape.sphere_radius();
    if (shape.is_cylinder()) {
        const Vec3 axis = shape.cylinder_frame().n;  // the normal turns only around it
        return (dp - axis * dot(dp, axis)) / shape.cylinder_radius();
    }
    const TriangleMesh& m = shape.mesh();
    if (m.normals.empty()) return Vec3(0.f);  // flat
    const uint32_t* idx = &m.indices[3 * hit.prim];
    const Vec3& p0 = m.positions[idx[0]];
    const Vec3 &n0 = m.normals[idx[0]], &n1 = m.normals[idx[1]], &n2 = m.normals[idx[2]];
    // The interpolated normal n0 w + n1 u + n2 v is linear in the barycentrics (u, v), which
    // are linear in p: this holds whether the uvs are degenerate or not.
    const Vec2 db = coordinates_in_tangents(dp, m.positions[idx[1]] - p0, m.positions[idx[2]] - p0);
    const Vec3 dn = (n1 - n0) * db.x + (n2 - n0) * db.y;
    const float w = 1.f - barycentrics.x - barycentrics.y;
    const float len = length(n0 * w + n1 * barycentrics.x + n2 * barycentrics.y);
    if (!(len > 0)) return Vec3(0.f);
    // The derivative of the normalized normal: the part perpendicular to it, over its length.
    const Vec3 ns = hit.sh.n;
    return (dn - ns * dot(ns, dn)) / len;
}

/// The pixel footprint of `hit` for a ray with a differential (pbrt-v3's
/// SurfaceInteraction::ComputeDifferentials): the neighbouring rays meet the hit's tangent
/// plane at p + dp, which gives uv's change through dpdu and dpdv and the normal's through the
/// shape's curvature.
PixelFootprint pixel_footprint(const Shape& shape, const Ray& ray, const Hit& hit,
                               Vec2 barycentrics) {
    const RayDifferential& rd = *ray.differential;
    PixelFootprint fp;
    Vec3 px, py;
    if (!meet_tangent_plane(hit.p, hit.ng, rd.dx_o, rd.dx_d, px) ||
        !meet_tangent_plane(hit.p, hit.ng, rd.dy_o, rd.dy_d, py))
        return fp;
    fp.valid = true;
    fp.dp_dx = px - hit.p;
    fp.dp_dy = py - hit.p;
    const Vec3 dpdv = hit_dpdv(shape, hit);
    fp.duv_dx = coordinates_in_tangents(fp.dp_dx, hit.dpdu, dpdv);
    fp.duv_dy = coordinates_in_tangents(fp.dp_dy, hit.dpdu, dpdv);
    fp.to_pixel_centre = rd.to_pixel_centre;
    const float side = shape.flip_normals() ? -1.f : 1.f;
    fp.dn_dx = normal_change(shape, hit, barycentrics, fp.dp_dx) * side;
    fp.dn_dy = normal_change(shape, hit, barycentrics, fp.dp_dy) * side;
    fp.dd_dx = rd.dx_d - ray.d;
    fp.dd_dy = rd.dy_d - ray.d;
    return fp;
}

}  // namespace

void Shape::fill_hit(const Ray& ray, float t, uint32_t prim, float u, float v, Hit& hit) const {
    // The tangent only for materials that read it and for footprints (which need it).
    const bool tangent = fills_tangent_ || ray.differential;
    // Every field of `hit` is written, so that an integrator may reuse one Hit for all of a
    // path's intersections (zeroing a fresh one per ray costs more than this store); only an
    // invalid footprint keeps its stale fields, which nothing reads (zeroing its 108 bytes
    // per hit took a twentieth of this function's instructions).
    hit.dpdu = Vec3();
    hit.t = t;
    hit.shape = this;
    hit.prim = prim;
    Vec3 ns;
    if (is_cylinder_) {
        fill_cylinder_hit(center_, cylinder_frame_, radius_, length_, ray.at(t), hit, ns);
        hit.ng = ns;
    } else if (is_sphere_) {
        const Vec3 local = normalize(ray.at(t) - center_);
        hit.p = center_ + local * radius_;
        hit.p_error = kRayOffsetScale * (max_abs_component(center_) + radius_);
        hit.ng = local;
        ns = local;
        const float phi = std::atan2(local.y, local.x);
        hit.uv = {(phi < 0 ? phi + 2 * kPi : phi) * kInvTwoPi,
                  std::acos(clamp(local.z, -1.f, 1.f)) * kInvPi};
        // d/du of center + r (sin theta cos phi, sin theta sin phi, cos theta) with
        // phi = 2pi u, in the world's axes as uv is (0 at the poles, where phi is undefined).
        if (tangent) hit.dpdu = Vec3(-local.y, local.x, 0.f) * (2 * kPi * radius_);
    } else {
        const uint32_t i0 = mesh_.indices[3 * prim], i1 = mesh_.indices[3 * prim + 1],
                       i2 = mesh_.indices[3 * prim + 2];
        const Vec3 &p0 = mesh_.positions[i0], &p1 = mesh_.positions[i1], &p2 = mesh_.positions[i2];
        const float w = 1.f - u - v;
        hit.p = p0 * w + p1 * u + p2 * v;
        hit.p_error = kRayOffsetScale * std::max({max_abs_component(p0), max_abs_component(p1),
                                                  max_abs_component(p2)});
        if (face_normals_) {  // (a rectangle's, a cube's)
            hit.ng = mesh_.normals[i0];
        } else {
            const Vec3 ng = cross(p1 - p0, p2 - p0);
            const float l = length(ng);
            hit.ng = l > 0 ? ng / l : Vec3(0, 0, 1);
        }
        ns = hit.ng;
        if (flat_normals_) {  // one normal per triangle (a flat-shaded mesh file's too)
            ns = mesh_.normals[i0];
        } else if (!mesh_.normals.empty()) {
            const Vec3 n = mesh_.normals[i0] * w + mesh_.normals[i1] * u + mesh_.normals[i2] * v;
            const float ln = length(n);
            if (ln > 0) ns = n / ln;
        }
        if (!mesh_.uvs.empty()) {
            const Vec2 &uv0 = mesh_.uvs[i0], &uv1 = mesh_.uvs[i1], &uv2 = mesh_.uvs[i2];
            hit.uv = uv0 * w + uv1 * u + uv2 * v;
            if (tangent) hit.dpdu = triangle_tangents(p0, p1, p2, uv0, uv1, uv2).dpdu;
        } else {
            hit.uv = {u, v};  // the barycentrics of p = p0 w + p1 u + p2 v
            if (tangent) hit.dpdu = p1 - p0;
        }
    }
    if (flip_normals_) {  // the inside becomes the outside; the parameterization stays
        hit.ng = -hit.ng;
        ns = -ns;
    }
    hit.sh = Frame(ns);
    hit.wi = hit.sh.to_local(-ray.d);
    if (ray.differential) {
        hit.footprint = pixel_footprint(*this, ray, hit, {u, v});
    } else {
        hit.footprint.valid = false;
        hit.footprint.light_cone = 0.f;
    }
}

struct Shape::AreaSampling {
    warp::AliasTable triangles;  // by area
    std::vector<Vec3> normal;    // unit, flipped with the shape
    std::vector<float> p_error;  // Hit::p_error of a point on the triangle
};

const Shape::AreaSampling& Shape::build_area_sampling() const {
    std::lock_guard<std::mutex> lock(area_sampling_mutex_);
    if (!area_sampling_owner_) {
        auto table = std::make_unique<AreaSampling>();
        const size_t n = mesh_.triangle_count();
        std::vector<double> areas(n);
        table->normal.resize(n);
        table->p_error.resize(n);
        for (size_t i = 0; i < n; ++i) {
            const Vec3& p0 = mesh_.positions[mesh_.indices[3 * i]];
            const Vec3& p1 = mesh_.positions[mesh_.indices[3 * i + 1]];
            const Vec3& p2 = mesh_.positions[mesh_.indices[3 * i + 2]];
            areas[i] = triangle_area(mesh_, i);
            const Vec3 normal = normalize(cross(p1 - p0, p2 - p0));
            table->normal[i] = flip_normals_ ? -normal : normal;
            table->p_error[i] =
                kRayOffsetScale *
                std::max({max_abs_component(p0), max_abs_component(p1), max_abs_component(p2)});
        }
        table->triangles = warp::AliasTable(areas);  // set_mesh() checked the total area
        area_sampling_owner_ = std::move(table);
        area_sampling_.store(area_sampling_owner_.get(), std::memory_order_release);
    }
    return *area_sampling_owner_;
}

ShapeSample Shape::sample_area(Vec2 u) const { return area_sample(u); }

[[gnu::always_inline]] inline ShapeSample Shape::area_sample(Vec2 u) const {
    ShapeSample s;
    if (is_cylinder_) {
        // Uniform in z and phi (Mitsuba's parameterization: u.x along the axis, u.y around).
        const Frame& f = cylinder_frame_;
        const float phi = 2.f * kPi * u.y;
        const Vec3 n = f.s * std::cos(phi) + f.t * std::sin(phi);
        s.p = center_ + f.n * (u.x * length_) + n * radius_;
        s.n = flip_normals_ ? -n : n;
        s.uv = {u.y, u.x};
        s.p_error = kRayOffsetScale * (std::max(max_abs_component(center_),
                                                max_abs_component(center_ + f.n * length_)) +
                                       radius_);
    } else if (is_sphere_) {
        const Vec3 d = warp::square_to_uniform_sphere(u);
        s.p = center_ + d * radius_;
        s.n = flip_normals_ ? -d : d;
        s.p_error = kRayOffsetScale * (max_abs_component(center_) + radius_);
    } else {
        const AreaSampling& table = area_sampling();
        float ux = u.x;
        const uint32_t tri = table.triangles.sample(ux);
        const Vec2 b = warp::square_to_uniform_triangle({ux, u.y});
        const Vec3& p0 = mesh_.positions[mesh_.indices[3 * tri]];
        const Vec3& p1 = mesh_.positions[mesh_.indices[3 * tri + 1]];
        const Vec3& p2 = mesh_.positions[mesh_.indices[3 * tri + 2]];
        s.p = p0 * (1.f - b.x - b.y) + p1 * b.x + p2 * b.y;
        s.n = table.normal[tri];
        s.uv = b;
        s.p_error = table.p_error[tri];
    }
    s.pdf = 1.f / area_;
    return s;
}

namespace {
// Solid-angle pdf from an area pdf: pdf_A * d^2 / |cos theta at the sampled point|, for the
// offset d from the reference point to a point of normal n, |d|^2 = dist2 > 0 and |d| = dist.
float area_to_solid_angle(float pdf_area, const Vec3& n, const Vec3& d, float dist2, float dist) {
    const float cos = std::abs(dot(n, d)) / dist;
    return cos > 0 ? pdf_area * dist2 / cos : 0.f;
}

// Sets s.wi and s.distance from `d`, the reference point's offset to s.p. Returns |d|^2 (0
// when the reference point is the sampled point).
float aim(ShapeSample& s, const Vec3& d) {
    const float dist2 = squared_length(d);
    if (!(dist2 > 0)) return 0.f;
    s.distance = std::sqrt(dist2);
    s.wi = d / s.distance;
    return dist2;
}
}  // namespace

// One result object, returned on every path (a failed sample is reset to ShapeSample{}): GCC
// then builds it in the caller's memory (NRVO) instead of copying it there at the end, where
// the copy's wide loads of fields just stored one by one waited for the stores.
ShapeSample Shape::sample_direct(const Vec3& ref, Vec2 u) const {
    ShapeSample s;
    if (is_sphere_) {
        const Vec3 to_center = center_ - ref;
        const float dist2 = squared_length(to_center);
        const float r2 = radius_ * radius_;
        if (dist2 > r2 * 1.0001f) {
            // Outside: sample the cone of directions the sphere subtends (uniform in solid angle).
            const float dist = std::sqrt(dist2);
            const float sin2_max = r2 / dist2;
            const float cos_max = safe_sqrt(1.f - sin2_max);
            const float one_minus_cos_max = sin2_max / (1.f + cos_max);
            const float cos_t = 1.f - u.x * one_minus_cos_max;
            const float sin2_t = std::max(0.f, 1.f - cos_t * cos_t);
            const float phi = 2.f * kPi * u.y;
            const Frame frame(to_center / dist);
            const float sin_t = std::sqrt(sin2_t);
            const Vec3 dir = frame.to_world({sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t});
            // Nearest intersection of ref + t*dir with the sphere.
            const float b = dist * cos_t;
            const float t = b - safe_sqrt(r2 - dist2 * sin2_t);
            s.p = ref + dir * t;
            const Vec3 n = normalize(s.p - center_);
            s.p = center_ + n * radius_;
            s.n = flip_normals_ ? -n : n;
            s.pdf = 1.f / (2.f * kPi * one_minus_cos_max);
            if (!(aim(s, s.p - ref) > 0)) s = ShapeSample{};
            return s;
        }
    }
    s = area_sample(u);  // converted to solid angle
    const Vec3 d = s.p - ref;
    const float dist2 = aim(s, d);
    if (dist2 > 0)
        s.pdf = area_to_solid_angle(s.pdf, s.n, d, dist2, s.distance);
    else
        s = ShapeSample{};
    return s;
}

float Shape::pdf_direct(const Vec3& ref, const Hit& hit) const {
    if (is_sphere_) {
        const float dist2 = squared_length(center_ - ref);
        const float r2 = radius_ * radius_;
        if (dist2 > r2 * 1.0001f) {
            const float sin2_max = r2 / dist2;
            const float cos_max = safe_sqrt(1.f - sin2_max);
            return 1.f / (2.f * kPi * sin2_max / (1.f + cos_max));
        }
    }
    const Vec3 d = hit.p - ref;
    const float dist2 = squared_length(d);
    if (!(dist2 > 0)) return 0.f;
    return area_to_solid_angle(1.f / area_, hit.ng, d, dist2, std::sqrt(dist2));
}

}  // namespace femto
