// Tests of the shape plugins against Mitsuba's conventions: rectangle, cube, sphere, disk and
// obj (ply has its own file, test_ply.cpp). Geometry is checked directly on the meshes the
// plugins hand to the host, and through hit records the host builds with Shape::fill_hit
// for rays cast by a brute-force intersector (shape_test_util.h).
//
// Tolerances: vertex data are floats computed from double transforms, so positions are
// exact to ~1 ulp of their magnitude (1e-6 relative; coordinates here are <= 10, hence 1e-5
// absolute); normalized normals to ~1e-7 (1e-6 used). Areas the host sums in double from
// float vertices: 1e-6 relative, except where stated.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "femto/error.h"
#include "femto/host.h"
#include "femto/plugin.h"
#include "femto/shape.h"
#include "femto/transform.h"
#include "shape_test_util.h"

namespace {

using femto::Hit;
using femto::PluginKind;
using femto::Properties;
using femto::Shape;
using femto::Transform;
using femto::TriangleMesh;
using femto::Vec2;
using femto::Vec3;
using femto_shape_test::brute_intersect;
using femto_shape_test::make_shape;
using femto_shape_test::ray_toward;
using femto_shape_test::ScratchDir;
using femto_shape_test::vec_near;

constexpr double kPiD = 3.14159265358979323846;

Vec3 triangle_normal(const TriangleMesh& m, size_t t) {
    const Vec3 p0 = m.positions[m.indices[3 * t]], p1 = m.positions[m.indices[3 * t + 1]],
               p2 = m.positions[m.indices[3 * t + 2]];
    return femto::normalize(femto::cross(p1 - p0, p2 - p0));
}

Vec3 triangle_centroid(const TriangleMesh& m, size_t t) {
    return (m.positions[m.indices[3 * t]] + m.positions[m.indices[3 * t + 1]] +
            m.positions[m.indices[3 * t + 2]]) /
           3.f;
}

double mesh_area(const TriangleMesh& m) {
    double a = 0;
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        const Vec3 p0 = m.positions[m.indices[3 * t]], p1 = m.positions[m.indices[3 * t + 1]],
                   p2 = m.positions[m.indices[3 * t + 2]];
        a += 0.5 * femto::length(femto::cross(p1 - p0, p2 - p0));
    }
    return a;
}

/// Every vertex normal equals the geometric normal of every triangle using it (flat shapes).
void expect_flat_consistent(const TriangleMesh& m, double tol) {
    ASSERT_EQ(m.normals.size(), m.positions.size());
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        const Vec3 ng = triangle_normal(m, t);
        for (int k = 0; k < 3; ++k)
            EXPECT_TRUE(vec_near(m.normals[m.indices[3 * t + k]], ng, tol)) << "triangle " << t;
    }
}

Transform matrix(const Transform::Matrix& m) { return Transform(m); }

std::string error_of(const Properties& props) {
    try {
        make_shape(props);
    } catch (const femto::SceneError& e) {
        return e.what();
    }
    return "(no error)";
}

// -- every shape ------------------------------------------------------------------------------

TEST(ShapeSchema, CommonShapeParametersAreDeclared) {
    for (const char* type : {"rectangle", "cube", "sphere", "disk", "cylinder", "obj", "ply"}) {
        const femto::PluginDescriptor& d = femto::find_plugin(PluginKind::Shape, type);
        EXPECT_EQ(d.kind, PluginKind::Shape);
        std::map<std::string, std::string> params;
        for (const auto& p : d.params) {
            EXPECT_TRUE(p.doc && *p.doc) << type << "." << p.name << " has no doc";
            params[p.name] = p.type;
        }
        EXPECT_EQ(params["flip_normals"], "boolean") << type;
        EXPECT_EQ(params["bsdf"], "bsdf") << type;
        EXPECT_EQ(params["emitter"], "emitter") << type;
        EXPECT_EQ(params["to_world"], "transform") << type;
    }
}

TEST(ShapeSchema, UnknownParameterIsRejected) {
    Properties props("rectangle", {});
    props.set_float("radius", 2);
    EXPECT_THROW(make_shape(props), femto::SceneError);
}

// -- rectangle --------------------------------------------------------------------------------

TEST(ShapeRectangle, UnitRectangleFollowsMitsuba) {
    auto s = make_shape(Properties("rectangle", {}));
    ASSERT_TRUE(s);
    const TriangleMesh& m = s->mesh();
    EXPECT_FALSE(s->is_sphere());
    EXPECT_EQ(m.triangle_count(), 2u);
    ASSERT_EQ(m.positions.size(), 4u);
    ASSERT_EQ(m.uvs.size(), 4u);
    int corners_found = 0;
    for (const Vec3 c : {Vec3(-1, -1, 0), Vec3(1, -1, 0), Vec3(1, 1, 0), Vec3(-1, 1, 0)})
        for (size_t i = 0; i < 4; ++i)
            if (m.positions[i] == c) {
                ++corners_found;
                EXPECT_EQ(m.uvs[i].x, (c.x + 1) / 2);
                EXPECT_EQ(m.uvs[i].y, (c.y + 1) / 2);
            }
    EXPECT_EQ(corners_found, 4);
    for (size_t t = 0; t < 2; ++t) EXPECT_TRUE(vec_near(triangle_normal(m, t), Vec3(0, 0, 1), 0));
    expect_flat_consistent(m, 0);
    EXPECT_EQ(s->surface_area(), 4.f);  // two right triangles of area 2, exact in floats

    // Rays hit where expected, with the host's hit record: uv = ((x+1)/2, (y+1)/2), ng = +z.
    for (const Vec2 xy : {Vec2(0.5f, 0.25f), Vec2(-0.75f, -0.5f), Vec2(0.9f, -0.9f),
                          Vec2(-0.9f, 0.9f), Vec2(0, 0)}) {
        Hit hit;
        ASSERT_TRUE(brute_intersect(*s, ray_toward({xy.x, xy.y, 3}, {xy.x, xy.y, 0}), hit));
        EXPECT_TRUE(vec_near(hit.p, {xy.x, xy.y, 0}, 1e-6));
        EXPECT_TRUE(vec_near(hit.ng, {0, 0, 1}, 0));
        EXPECT_NEAR(hit.uv.x, (xy.x + 1) / 2, 1e-6);
        EXPECT_NEAR(hit.uv.y, (xy.y + 1) / 2, 1e-6);
        EXPECT_NEAR(hit.t, 3.f, 1e-6);
    }
    Hit miss;
    EXPECT_FALSE(brute_intersect(*s, ray_toward({1.01f, 0, 3}, {1.01f, 0, 0}), miss));
}

TEST(ShapeRectangle, ToWorldPlacesScalesAndRotates) {
    // scale(2,3,1), then 90 degrees about +x (z -> -y... +z maps to (0,-1,0)), then translate.
    const Transform t = Transform::translate({1, 2, 3}) * Transform::rotate({1, 0, 0}, 90) *
                        Transform::scale({2, 3, 1});
    Properties props("rectangle", {});
    props.set_transform("to_world", t);
    auto s = make_shape(props);
    ASSERT_TRUE(s);
    const TriangleMesh& m = s->mesh();
    // Local (x, y, 0) -> (1 + 2x, 2, 3 + 3y).
    for (size_t i = 0; i < 4; ++i) {
        const Vec3 p = m.positions[i];
        const float x = (p.x - 1) / 2, y = (p.z - 3) / 3;
        EXPECT_NEAR(std::abs(x), 1, 1e-5);
        EXPECT_NEAR(std::abs(y), 1, 1e-5);
        EXPECT_NEAR(p.y, 2, 1e-5);
        EXPECT_NEAR(m.uvs[i].x, (x + 1) / 2, 1e-5);
        EXPECT_NEAR(m.uvs[i].y, (y + 1) / 2, 1e-5);
    }
    for (size_t t2 = 0; t2 < 2; ++t2)
        EXPECT_TRUE(vec_near(triangle_normal(m, t2), {0, -1, 0}, 1e-6));
    expect_flat_consistent(m, 1e-6);
    EXPECT_NEAR(s->surface_area(), 24.f, 24 * 1e-6);
}

TEST(ShapeRectangle, MirroringTransformKeepsWindingConsistent) {
    // det < 0. scale(-1,1,1): the plane's normal (inverse transpose) stays +z; scale(1,1,-1)
    // turns it to -z. Either way the geometric normal must agree with the vertex normals.
    for (const auto& [scale, n] : std::vector<std::pair<Vec3, Vec3>>{
             {{-1, 1, 1}, {0, 0, 1}}, {{1, 1, -1}, {0, 0, -1}}, {{-2, 3, 1}, {0, 0, 1}}}) {
        Properties props("rectangle", {});
        props.set_transform("to_world", Transform::scale(scale));
        auto s = make_shape(props);
        ASSERT_TRUE(s);
        for (size_t t = 0; t < 2; ++t) EXPECT_TRUE(vec_near(triangle_normal(s->mesh(), t), n, 0));
        expect_flat_consistent(s->mesh(), 0);
        EXPECT_NEAR(s->surface_area(), 4 * std::abs(scale.x * scale.y), 1e-5);
    }
}

TEST(ShapeRectangle, FlipNormals) {
    for (const bool flip : {false, true}) {
        Properties props("rectangle", {});
        props.set_bool("flip_normals", flip);
        auto s = make_shape(props);
        ASSERT_TRUE(s);
        EXPECT_EQ(s->flip_normals(), flip);
        const Vec3 expected = flip ? Vec3(0, 0, -1) : Vec3(0, 0, 1);
        Hit hit;
        ASSERT_TRUE(brute_intersect(*s, ray_toward({0.2f, 0.3f, 2}, {0.2f, 0.3f, 0}), hit));
        EXPECT_TRUE(vec_near(hit.ng, expected, 0));
        EXPECT_TRUE(vec_near(hit.sh.n, expected, 0));
        EXPECT_TRUE(vec_near(s->sample_area({0.3f, 0.6f}).n, expected, 1e-6));
    }
}

// -- cube -------------------------------------------------------------------------------------

TEST(ShapeCube, UnitCubeFollowsMitsuba) {
    auto s = make_shape(Properties("cube", {}));
    ASSERT_TRUE(s);
    const TriangleMesh& m = s->mesh();
    EXPECT_EQ(m.triangle_count(), 12u);
    EXPECT_EQ(m.positions.size(), 24u);  // 4 per face: flat faces with their own uvs
    ASSERT_EQ(m.uvs.size(), 24u);
    for (const Vec3& p : m.positions)
        for (int k = 0; k < 3; ++k) EXPECT_EQ(std::abs(p[k]), 1.f);
    for (const Vec2& uv : m.uvs) {
        EXPECT_TRUE(uv.x == 0 || uv.x == 1);
        EXPECT_TRUE(uv.y == 0 || uv.y == 1);
    }
    EXPECT_EQ(s->surface_area(), 24.f);
    std::map<std::tuple<float, float, float>, double> face_area;
    for (size_t t = 0; t < 12; ++t) {
        const Vec3 n = triangle_normal(m, t);
        const Vec3 c = triangle_centroid(m, t);
        EXPECT_GT(femto::dot(n, c), 0.f) << "triangle " << t << " faces inward";
        // Axis aligned, and every vertex lies on the face plane the normal names.
        int axis = -1;
        for (int k = 0; k < 3; ++k)
            if (std::abs(n[k]) == 1.f) axis = k;
        ASSERT_GE(axis, 0) << "triangle " << t << " is not axis aligned";
        for (int k = 0; k < 3; ++k) EXPECT_EQ(m.positions[m.indices[3 * t + k]][axis], n[axis]);
        const Vec3 p0 = m.positions[m.indices[3 * t]], p1 = m.positions[m.indices[3 * t + 1]],
                   p2 = m.positions[m.indices[3 * t + 2]];
        face_area[{n.x, n.y, n.z}] += 0.5 * femto::length(femto::cross(p1 - p0, p2 - p0));
    }
    EXPECT_EQ(face_area.size(), 6u);
    for (const auto& [n, a] : face_area) EXPECT_EQ(a, 4.0);
    expect_flat_consistent(m, 0);

    // From outside, a ray toward the center hits the face it comes from, normal outward;
    // from the center, a ray leaves through a face whose normal points along it.
    for (int axis = 0; axis < 3; ++axis)
        for (const float sign : {-1.f, 1.f}) {
            Vec3 dir;
            dir[axis] = sign;
            Hit hit;
            ASSERT_TRUE(brute_intersect(*s,
                                        ray_toward(dir * 5.f + Vec3(0.1f, 0.2f, 0.3f) * 0.5f,
                                                   Vec3(0.1f, 0.2f, 0.3f) * 0.5f),
                                        hit));
            EXPECT_TRUE(vec_near(hit.ng, dir, 0));
            EXPECT_NEAR(hit.t, 4.f, 0.3f);
            ASSERT_TRUE(
                brute_intersect(*s, femto::Ray{Vec3(0.f), dir, 0.f, femto::kInfinity}, hit));
            EXPECT_TRUE(vec_near(hit.ng, dir, 0));
            EXPECT_NEAR(hit.t, 1.f, 1e-6);
        }
}

TEST(ShapeCube, NormalsUnderNonUniformScaleAndShear) {
    // A general affine map: non-uniform scale, shear and translation.
    const Transform::Matrix mat = {
        {{2.0, 0.5, 0.0, 1.0}, {0.0, 1.0, 0.3, -2.0}, {0.2, 0.0, 3.0, 0.5}, {0.0, 0.0, 0.0, 1.0}}};
    const Transform t = matrix(mat);
    Properties props("cube", {});
    props.set_transform("to_world", t);
    auto s = make_shape(props);
    ASSERT_TRUE(s);
    const TriangleMesh& m = s->mesh();
    const Vec3 center = t.point(Vec3(0.f));
    for (size_t tri = 0; tri < m.triangle_count(); ++tri) {
        const Vec3 ng = triangle_normal(m, tri);
        // The image of a convex body is convex: an outward face normal points away from the
        // image of the center.
        EXPECT_GT(femto::dot(ng, triangle_centroid(m, tri) - center), 0.f) << tri;
        const Vec3 p0 = m.positions[m.indices[3 * tri]], p1 = m.positions[m.indices[3 * tri + 1]],
                   p2 = m.positions[m.indices[3 * tri + 2]];
        for (int k = 0; k < 3; ++k) {
            const Vec3 n = m.normals[m.indices[3 * tri + k]];
            EXPECT_NEAR(femto::length(n), 1.f, 1e-6);
            // Inverse-transpose normals stay perpendicular to the (sheared) faces.
            EXPECT_NEAR(femto::dot(n, femto::normalize(p1 - p0)), 0.f, 1e-5) << tri;
            EXPECT_NEAR(femto::dot(n, femto::normalize(p2 - p0)), 0.f, 1e-5) << tri;
            EXPECT_GT(femto::dot(n, ng), 1.f - 1e-5f) << tri;
        }
    }
    // Area: each pair of opposite faces is a parallelogram spanned by 2 M e_i and 2 M e_j.
    double area = 0;
    for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j) {
            const double a[3] = {mat[0][i], mat[1][i], mat[2][i]};
            const double b[3] = {mat[0][j], mat[1][j], mat[2][j]};
            const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                                 a[0] * b[1] - a[1] * b[0]};
            area += 2 * 4 * std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        }
    EXPECT_NEAR(s->surface_area(), area, area * 1e-6);
}

TEST(ShapeCube, MirroredCubeStaysOutward) {
    const Transform t = Transform::rotate({0, 1, 1}, 35) * Transform::scale({-1, 2, 0.5f});
    ASSERT_LT(t.det3(), 0);
    Properties props("cube", {});
    props.set_transform("to_world", t);
    auto s = make_shape(props);
    ASSERT_TRUE(s);
    for (size_t tri = 0; tri < 12; ++tri)
        EXPECT_GT(femto::dot(triangle_normal(s->mesh(), tri), triangle_centroid(s->mesh(), tri)),
                  0.f)
            << tri;
    expect_flat_consistent(s->mesh(), 1e-6);
    EXPECT_NEAR(s->surface_area(), 28.0, 28 * 1e-6);  // 8 (|c0 x c1| + |c0 x c2| + |c1 x c2|)
}

// -- sphere -----------------------------------------------------------------------------------

TEST(ShapeSphere, DefaultsAndParameters) {
    auto unit = make_shape(Properties("sphere", {}));
    ASSERT_TRUE(unit);
    EXPECT_TRUE(unit->is_sphere());
    EXPECT_TRUE(vec_near(unit->sphere_center(), Vec3(0.f), 0));
    EXPECT_EQ(unit->sphere_radius(), 1.f);
    EXPECT_NEAR(unit->surface_area(), 4 * kPiD, 4 * kPiD * 1e-6);

    Properties props("sphere", {});
    props.set_point("center", {1, 2, 3});
    props.set_float("radius", 0.5);
    auto s = make_shape(props);
    ASSERT_TRUE(s);
    EXPECT_TRUE(vec_near(s->sphere_center(), {1, 2, 3}, 0));
    EXPECT_EQ(s->sphere_radius(), 0.5f);
    EXPECT_NEAR(s->surface_area(), kPiD, kPiD * 1e-6);

    // The host's hit: outward normal, flipped with flip_normals.
    Hit hit;
    ASSERT_TRUE(brute_intersect(*s, ray_toward({1, 2, 10}, {1, 2, 3}), hit));
    EXPECT_TRUE(vec_near(hit.p, {1, 2, 3.5f}, 1e-5));
    EXPECT_TRUE(vec_near(hit.ng, {0, 0, 1}, 1e-5));
    props.set_bool("flip_normals", true);
    auto flipped = make_shape(props);
    ASSERT_TRUE(brute_intersect(*flipped, ray_toward({1, 2, 10}, {1, 2, 3}), hit));
    EXPECT_TRUE(vec_near(hit.ng, {0, 0, -1}, 1e-5));
}

TEST(ShapeSphere, ToWorldMovesCenterAndScalesRadius) {
    const Transform t = Transform::translate({1, 0, 0}) * Transform::rotate({0, 0, 1}, 30) *
                        Transform::rotate({1, 0, 0}, 90) * Transform::scale({2, 2, 2});
    Properties props("sphere", {});
    props.set_point("center", {0, 0, 1});
    props.set_float("radius", 0.5);
    props.set_transform("to_world", t);
    auto s = make_shape(props);
    ASSERT_TRUE(s);
    // (0,0,1) -> scale (0,0,2) -> rot x 90: (0,-2,0) -> rot z 30: (1, -sqrt(3), 0) -> +x.
    EXPECT_TRUE(vec_near(s->sphere_center(), {2, -std::sqrt(3.f), 0}, 1e-5));
    EXPECT_NEAR(s->sphere_radius(), 1.f, 1e-6);
    EXPECT_NEAR(s->surface_area(), 4 * kPiD, 4 * kPiD * 1e-5);

    // A mirror with uniform magnitude is still a similarity.
    Properties mirrored("sphere", {});
    mirrored.set_transform("to_world", Transform::scale({-3, 3, 3}));
    auto m = make_shape(mirrored);
    ASSERT_TRUE(m);
    EXPECT_NEAR(m->sphere_radius(), 3.f, 1e-6);
}

TEST(ShapeSphere, RejectsNonUniformScaleAndBadRadius) {
    for (const Transform& t : {Transform::scale({1, 2, 1}),
                               Transform::rotate({1, 2, 3}, 40) * Transform::scale({1, 1, 1.01f}),
                               Transform(Transform::Matrix{
                                   {{1, 0.5, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}})}) {
        Properties props("sphere", {});
        props.set_transform("to_world", t);
        const std::string msg = error_of(props);
        EXPECT_NE(msg.find("uniform"), std::string::npos) << msg;
    }
    for (const double r : {0.0, -1.0}) {
        Properties props("sphere", {});
        props.set_float("radius", r);
        EXPECT_NE(error_of(props).find("radius"), std::string::npos);
    }
}

// -- disk -------------------------------------------------------------------------------------

TEST(ShapeDisk, AreaEqualsCircleArea) {
    auto s = make_shape(Properties("disk", {}));
    ASSERT_TRUE(s);
    // The fan is built so that its area is exactly pi; what remains is float rounding of the
    // vertices (~6e-8 relative each), far below the 1e-5 asked for.
    EXPECT_NEAR(s->surface_area(), kPiD, kPiD * 1e-5);
    EXPECT_NEAR(mesh_area(s->mesh()), kPiD, kPiD * 1e-5);

    for (const auto& [scale, area] : std::vector<std::pair<Vec3, double>>{
             {{2, 2, 1}, 4 * kPiD}, {{2, 3, 1}, 6 * kPiD}, {{0.1f, 0.1f, 5}, 0.01 * kPiD}}) {
        Properties props("disk", {});
        props.set_transform("to_world", Transform::translate({1, 2, 3}) * Transform::scale(scale));
        auto d = make_shape(props);
        ASSERT_TRUE(d);
        EXPECT_NEAR(d->surface_area(), area, area * 1e-5);
    }
}

TEST(ShapeDisk, GeometryNormalsAndPolarUvs) {
    auto s = make_shape(Properties("disk", {}));
    ASSERT_TRUE(s);
    const TriangleMesh& m = s->mesh();
    const double n_seg = double(m.triangle_count());
    EXPECT_EQ(m.triangle_count(), 256u);
    const double r_vertex = std::sqrt(kPiD / (0.5 * n_seg * std::sin(2 * kPiD / n_seg)));
    double max_r = 0;
    for (size_t i = 0; i < m.positions.size(); ++i) {
        const Vec3 p = m.positions[i];
        EXPECT_EQ(p.z, 0.f);
        const double r = std::hypot(p.x, p.y);
        max_r = std::max(max_r, r);
        if (r > 0.5) {  // a rim vertex: uv = (1, phi / 2pi)
            double phi = std::atan2(p.y, p.x);
            if (phi < 0) phi += 2 * kPiD;
            EXPECT_EQ(m.uvs[i].x, 1.f);
            const double v = m.uvs[i].y;
            EXPECT_TRUE(std::abs(v - phi / (2 * kPiD)) < 1e-6 ||
                        (phi < 1e-6 && std::abs(v - 1) < 1e-6))
                << "rim vertex " << i << " phi " << phi << " v " << v;
        } else {
            EXPECT_EQ(m.uvs[i].x, 0.f);
        }
    }
    EXPECT_NEAR(max_r, r_vertex, 1e-6);
    for (size_t t = 0; t < m.triangle_count(); ++t)
        EXPECT_TRUE(vec_near(triangle_normal(m, t), {0, 0, 1}, 1e-6)) << t;
    expect_flat_consistent(m, 1e-6);

    // Hits inside the unit circle; the interpolated uv approximates (r, phi / 2pi): r to the
    // fan's relative deviation from the circle (< 1e-4), v to half a segment (1 / 2N) as
    // the angle is interpolated linearly across each triangle.
    for (const double r : {0.1, 0.5, 0.97})
        for (const double phi : {0.3, 1.7, 3.0, 4.4, 6.2}) {
            const Vec3 p(float(r * std::cos(phi)), float(r * std::sin(phi)), 0.f);
            Hit hit;
            ASSERT_TRUE(brute_intersect(*s, ray_toward(p + Vec3(0, 0, 1), p), hit));
            EXPECT_TRUE(vec_near(hit.ng, {0, 0, 1}, 1e-6));
            EXPECT_NEAR(hit.uv.x, r, 2e-4);
            EXPECT_NEAR(hit.uv.y, phi / (2 * kPiD), 0.5 / n_seg + 1e-6);
        }
    Hit miss;
    EXPECT_FALSE(brute_intersect(*s, ray_toward({1.001f, 0.01f, 1}, {1.001f, 0.01f, 0}), miss));
}

TEST(ShapeDisk, MirroredDiskKeepsWindingConsistent) {
    Properties props("disk", {});
    props.set_transform("to_world", Transform::scale({1, 1, -1}));
    auto s = make_shape(props);
    ASSERT_TRUE(s);
    for (size_t t = 0; t < s->mesh().triangle_count(); ++t)
        EXPECT_TRUE(vec_near(triangle_normal(s->mesh(), t), {0, 0, -1}, 1e-6));
    expect_flat_consistent(s->mesh(), 1e-6);
}

// -- obj --------------------------------------------------------------------------------------

// A 2x1 quad in z = 0 (uvs, one file normal +z and one deliberately unnormalized tilted one)
// and a triangle in y = 0 given by negative (relative) indices and without normals.
constexpr const char* kObj = R"(# test mesh
mtllib materials_that_do_not_exist.mtl
o quad
v 0 0 0
v 2 0 0
v 2 1 0
v 0 1 0
v 0 0 1
vt 0 0
vt 1 0
vt 1 1
vt 0 0.25
vn 0 0 1
vn 0 2 2
usemtl whatever
f 1/1/1 2/2/1 3/3/1 4/4/2
o tri
f -5/1 -4/2 -1/4
)";

std::vector<size_t> vertices_at(const TriangleMesh& m, const Vec3& p) {
    std::vector<size_t> out;
    for (size_t i = 0; i < m.positions.size(); ++i)
        if (vec_near(m.positions[i], p, 1e-6)) out.push_back(i);
    return out;
}

TEST(ShapeObj, LoadsPolygonsUvsAndNormals) {
    ScratchDir dir;
    Properties props("obj", {});
    props.set_string("filename", dir.write("mesh.obj", kObj));
    auto s = make_shape(props);
    ASSERT_TRUE(s);
    const TriangleMesh& m = s->mesh();
    EXPECT_EQ(m.triangle_count(), 3u);  // quad -> 2 + triangle
    EXPECT_EQ(m.positions.size(), 7u);  // distinct (v, vt, vn) triples
    EXPECT_NEAR(s->surface_area(), 3.0, 3e-6);
    ASSERT_EQ(m.uvs.size(), m.positions.size());
    ASSERT_EQ(m.normals.size(), m.positions.size());

    // Quad: v flipped (Mitsuba's flip_tex_coords default), file normals used and normalized.
    for (const size_t i : vertices_at(m, {2, 1, 0})) {
        EXPECT_EQ(m.uvs[i].x, 1.f);
        EXPECT_EQ(m.uvs[i].y, 0.f);
        EXPECT_TRUE(vec_near(m.normals[i], {0, 0, 1}, 1e-6));
    }
    ASSERT_EQ(vertices_at(m, {0, 1, 0}).size(), 1u);
    const size_t v4 = vertices_at(m, {0, 1, 0})[0];
    EXPECT_EQ(m.uvs[v4].y, 0.75f);
    EXPECT_TRUE(vec_near(m.normals[v4], Vec3(0, 1, 1) / std::sqrt(2.f), 1e-6));

    // Triangle without file normals: smooth, angle-weighted normals per position. Vertex 5
    // only touches the triangle (normal -y); vertex 1 sees the quad (+z) over a right angle
    // and the triangle (-y) over a right angle.
    ASSERT_EQ(vertices_at(m, {0, 0, 1}).size(), 1u);
    EXPECT_TRUE(vec_near(m.normals[vertices_at(m, {0, 0, 1})[0]], {0, -1, 0}, 1e-6));
    const auto v1 = vertices_at(m, {0, 0, 0});
    ASSERT_EQ(v1.size(), 2u);  // the quad's (with vn) and the triangle's (without)
    bool file_normal = false, computed = false;
    for (const size_t i : v1) {
        file_normal |= bool(vec_near(m.normals[i], {0, 0, 1}, 1e-6));
        computed |= bool(vec_near(m.normals[i], Vec3(0, -1, 1) / std::sqrt(2.f), 1e-6));
    }
    EXPECT_TRUE(file_normal);
    EXPECT_TRUE(computed);
    // Geometric normals follow the file's winding: quad +z, triangle -y.
    int up = 0, side = 0;
    for (size_t t = 0; t < 3; ++t) {
        up += vec_near(triangle_normal(m, t), {0, 0, 1}, 1e-6) ? 1 : 0;
        side += vec_near(triangle_normal(m, t), {0, -1, 0}, 1e-6) ? 1 : 0;
    }
    EXPECT_EQ(up, 2);
    EXPECT_EQ(side, 1);
}

TEST(ShapeObj, Options) {
    ScratchDir dir;
    const std::string file = dir.write("mesh.obj", kObj);
    {
        Properties props("obj", {});
        props.set_string("filename", file);
        props.set_bool("face_normals", true);
        props.set_bool("flip_tex_coords", false);
        auto s = make_shape(props);
        ASSERT_TRUE(s);
        EXPECT_TRUE(s->mesh().normals.empty());
        ASSERT_EQ(vertices_at(s->mesh(), {0, 1, 0}).size(), 1u);
        EXPECT_EQ(s->mesh().uvs[vertices_at(s->mesh(), {0, 1, 0})[0]].y, 0.25f);
    }
    {
        Properties props("obj", {});
        props.set_string("filename", file);
        props.set_transform("to_world", Transform::translate({0, 0, 5}) *
                                            Transform::scale({1, 1, -1}));  // a mirror
        auto s = make_shape(props);
        ASSERT_TRUE(s);
        const TriangleMesh& m = s->mesh();
        EXPECT_EQ(vertices_at(m, {2, 1, 5}).size(), 1u);
        EXPECT_EQ(vertices_at(m, {0, 0, 4}).size(), 1u);
        // Mirrored in z: the quad's normal becomes -z, and the winding follows.
        for (size_t t = 0; t < m.triangle_count(); ++t)
            for (int k = 0; k < 3; ++k) {
                const size_t i = m.indices[3 * t + k];
                if (vec_near(m.normals[i], {0, 0, -1}, 1e-6)) {
                    EXPECT_TRUE(vec_near(triangle_normal(m, t), {0, 0, -1}, 1e-6));
                }
            }
    }
}

// A triangle whose three vertex normals are equal shades with that normal as it is (not
// interpolated and normalised again); other triangles interpolate theirs.
TEST(ShapeObj, EqualVertexNormalsAreTheTrianglesNormal) {
    ScratchDir dir;
    auto quad_with_normal = [&](const std::string& normal_of_vertex_3) {
        Properties props("obj", {});
        props.set_string(
            "filename",
            dir.write("quad.obj", "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nvn 0.1 0.2 3\nvn " +
                                      normal_of_vertex_3 +
                                      "\nf 1//1 2//1 3//2\nf 1//1 3//2 4//1\n"));
        return make_shape(props);
    };
    const femto::Ray down{{0.5f, 0.5f, 1.f}, {0, 0, -1}};
    for (const auto& [normal, flat] :
         {std::pair{"0.1 0.2 3", true}, std::pair{"0.1 0.201 3", false}}) {
        auto s = quad_with_normal(normal);
        ASSERT_TRUE(s);
        ASSERT_EQ(s->mesh().normals.size(), 4u);
        const Vec3 n0 = s->mesh().normals[0];
        // Interpolated and normalised again, equal normals come back changed in the last bits
        // at some of these points.
        int equal = 0;
        for (int i = 1; i < 16; ++i)
            for (int j = 1; i + j < 16; ++j) {
                Hit hit;
                s->fill_hit(down, 1.f, 0, float(i) / 16.f, float(j) / 16.f, hit);
                EXPECT_TRUE(vec_near(hit.ng, {0, 0, 1}, 0)) << normal;
                EXPECT_TRUE(vec_near(hit.sh.n, n0, 1e-3)) << normal;
                equal += hit.sh.n == n0;
            }
        EXPECT_EQ(equal == 105, flat) << normal << ": " << equal << " of 105 points";
    }
}

// A flat mesh whose vertex normals are its face normals gives hits that normal as their
// geometric normal too (without normalising the face's cross product again); a normal against
// the winding, or tilted from the face, leaves the geometric normal the winding's.
TEST(ShapeObj, FaceNormalsAreTheGeometricNormal) {
    ScratchDir dir;
    auto quad_with_normal = [&](const std::string& normal) {
        Properties props("obj", {});
        props.set_string("filename",
                         dir.write("quad.obj", "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nvn " + normal +
                                                   "\nf 1//1 2//1 3//1\nf 1//1 3//1 "
                                                   "4//1\n"));
        return make_shape(props);
    };
    const femto::Ray down{{0.5f, 0.5f, 1.f}, {0, 0, -1}};
    const Vec3 tilted = normalize(Vec3(0.f, 1e-3f, 1.f));  // a thousandth of a radian off
    for (const auto& [normal, shading] : {std::pair{std::string("0 0 1"), Vec3(0, 0, 1)},
                                          std::pair{std::string("0 0 -1"), Vec3(0, 0, -1)},
                                          std::pair{std::string("0 0.001 1"), tilted}}) {
        auto s = quad_with_normal(normal);
        ASSERT_TRUE(s);
        for (uint32_t prim = 0; prim < 2; ++prim) {
            Hit hit;
            s->fill_hit(down, 1.f, prim, 0.25f, 0.25f, hit);
            EXPECT_TRUE(vec_near(hit.ng, {0, 0, 1}, 0)) << normal;
            EXPECT_TRUE(vec_near(hit.sh.n, shading, 1e-7f)) << normal;
        }
    }
}

TEST(ShapeObj, BadFiles) {
    ScratchDir dir;
    auto error_for = [&](const std::string& content) {
        Properties props("obj", {});
        props.set_string("filename", dir.write("bad.obj", content));
        return error_of(props);
    };
    {
        Properties props("obj", {});
        props.set_string("filename", dir.path("missing.obj"));
        const std::string msg = error_of(props);
        EXPECT_NE(msg.find("cannot open"), std::string::npos) << msg;
        EXPECT_NE(msg.find("missing.obj"), std::string::npos) << msg;
    }
    {
        Properties props("obj", {});
        EXPECT_NE(error_of(props).find("filename"), std::string::npos);  // required
    }
    EXPECT_NE(error_for("v 0 0 0\nv 1 0 0\nv 0 1 0\n").find("no faces"), std::string::npos);
    EXPECT_NE(error_for("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").find("bad.obj"), std::string::npos);
    EXPECT_NE(error_for("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/5 2/1 3/1\nvt 0 0\n").find("bad.obj"),
              std::string::npos);
    EXPECT_NE(error_for("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -7\n").find("bad.obj"),
              std::string::npos);
    EXPECT_NE(error_for("").find("bad.obj"), std::string::npos);
}

TEST(ShapeObj, CornellBoxLuminaire) {
    // A real Blender export from the Mitsuba Cornell box (tests may read ../shared).
    const std::string file =
        std::string(FEMTO_SHARED_DIR) + "/compat-scenes/mitsuba06-cbox/meshes/cbox_luminaire.obj";
    if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " not found";
    Properties props("obj", {});
    props.set_string("filename", file);
    auto s = make_shape(props);
    ASSERT_TRUE(s);
    EXPECT_EQ(s->mesh().triangle_count(), 2u);
    EXPECT_NEAR(s->surface_area(), 130.0 * 105.0, 130.0 * 105.0 * 1e-6);
    for (size_t t = 0; t < 2; ++t)
        EXPECT_TRUE(vec_near(triangle_normal(s->mesh(), t), {0, -1, 0}, 1e-6));
    for (const Vec3& n : s->mesh().normals) EXPECT_TRUE(vec_near(n, {0, -1, 0}, 1e-6));
}

}  // namespace
