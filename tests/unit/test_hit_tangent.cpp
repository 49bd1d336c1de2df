// Hit::dpdu, the world-space derivative of the position along the texture's u, for every shape
// kind the host traces: triangle meshes with and without uvs, analytic spheres and cylinders,
// and an instanced mesh under a rotation and a non-uniform scale. Each is checked through the
// scene's own intersection (Embree) at random points against central finite differences of
// (p, uv) between neighbouring hits, and for lying in the tangent plane; flip_normals leaves it
// unchanged, a sphere's poles give zero, degenerate triangle uvs give zero.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <optional>
#include <random>
#include <string>

#include "btf_test_util.h"
#include "femto/host.h"
#include "femto/scene.h"
#include "femto/shape.h"
#include "femto/transform.h"
#include "scene_util.h"
#include "shape_test_util.h"

namespace {

using femto::Hit;
using femto::Properties;
using femto::Ray;
using femto::Scene;
using femto::Vec2;
using femto::Vec3;
using femto_shape_test::brute_intersect;
using femto_shape_test::make_shape;
using femto_shape_test::ScratchDir;
using femto_shape_test::vec_near;

// A pyramid over a 2 x 1.5 base with skewed, non-orthogonal uvs, one face's uvs mirrored
// (negative determinant): five faces, six triangles, each with its own dp/du.
constexpr const char* kPyramidWithUvs = R"(v 0 0 0
v 2 0 0
v 2 1.5 0
v 0 1.5 0
v 1 0.75 1.2
vt 0.1 0.2
vt 0.9 0.1
vt 0.6 0.8
vt 0.3 1.3
vt 1.7 0.4
vt -0.5 0.6
f 1/1 2/2 5/3
f 2/2 3/5 5/3
f 3/4 4/6 5/1
f 4/3 1/5 5/2
f 1/6 4/2 3/3 2/1
)";

constexpr const char* kPyramidWithoutUvs = R"(v 0 0 0
v 2 0 0
v 2 1.5 0
v 0 1.5 0
v 1 0.75 1.2
f 1 2 5
f 2 3 5
f 3 4 5
f 4 1 5
f 1 4 3 2
)";

const Vec3 kPyramidCentre(1.f, 0.75f, 0.4f);

// The shapes wear a BTF, a material that reads Hit::dpdu (Bsdf::uses_tangent()): hits on
// other materials may leave it zero (HitTangent.OnlyMaterialsThatReadItGetIt).
const std::string& tangent_bsdf() {
    static const std::string xml =
        "<bsdf type=\"btf\"><string name=\"filename\" value=\"" +
        femto::test::write_btf(femto::test::small_btf_a(), "hit_tangent", "a.dfmf") + "\"/></bsdf>";
    return xml;
}

std::string obj_shape(const std::string& file, const std::string& extra = "") {
    return "<shape type=\"obj\"><string name=\"filename\" value=\"" + file + "\"/>" + extra +
           tangent_bsdf() + "</shape>";
}

std::string sphere_shape(const std::string& extra = "") {
    return "<shape type=\"sphere\"><point name=\"center\" x=\"0.3\" y=\"-0.2\" z=\"0.1\"/>"
           "<float name=\"radius\" value=\"0.8\"/><transform name=\"to_world\"><rotate x=\"1\" "
           "y=\"1\" angle=\"35\"/></transform>" +
           extra + tangent_bsdf() + "</shape>";
}

std::string cylinder_shape(const std::string& extra = "") {
    return "<shape type=\"cylinder\"><point name=\"p0\" x=\"0.2\" y=\"-0.1\" z=\"-0.5\"/>"
           "<point name=\"p1\" x=\"-0.3\" y=\"0.4\" z=\"1.0\"/><float name=\"radius\" "
           "value=\"0.7\"/>" +
           extra + tangent_bsdf() + "</shape>";
}

std::unique_ptr<Scene> load(const std::string& shapes) {
    return femto::load_scene_string(femto::test::scene_xml(shapes));
}

/// The hit of a ray from `from` toward `target` when it lands on the same primitive of the
/// same shape as `at` (else nullopt: the neighbour crossed an edge or missed).
std::optional<Hit> neighbour(const Scene& scene, const Vec3& from, const Vec3& target,
                             const Hit& at) {
    Hit hit;
    if (!scene.intersect(Ray{from, normalize(target - from), 0.f, femto::kInfinity}, hit) ||
        hit.shape != at.shape || hit.prim != at.prim)
        return std::nullopt;
    return hit;
}

/// dp/du at `hit` from central differences: hits a step `h` either way along two tangents of
/// the geometric normal (not the shading frame's, which smooth normals tilt off the surface:
/// rays through such targets land along the view direction, making the chords collinear) give
/// two chords dp_k = p(+) - p(-) with their uv differences duv_k; solving
/// dp_k = dpdu duv_k.x + dpdv duv_k.y (k = 1, 2) for dpdu. Nullopt when a neighbour left the
/// primitive or the chord crosses u's seam (u jumps by ~1 there).
std::optional<Vec3> finite_difference_dpdu(const Scene& scene, const Vec3& from, const Hit& hit,
                                           float h) {
    Vec3 dp[2];
    Vec2 duv[2];
    const femto::Frame tangents(hit.ng);
    const Vec3 axes[2] = {tangents.s, tangents.t};
    for (int k = 0; k < 2; ++k) {
        const auto plus = neighbour(scene, from, hit.p + axes[k] * h, hit);
        const auto minus = neighbour(scene, from, hit.p - axes[k] * h, hit);
        if (!plus || !minus) return std::nullopt;
        dp[k] = plus->p - minus->p;
        duv[k] = plus->uv - minus->uv;
        if (std::abs(duv[k].x) > 0.25f) return std::nullopt;
    }
    const float det = duv[0].x * duv[1].y - duv[0].y * duv[1].x;
    if (det == 0) return std::nullopt;
    return (dp[0] * duv[1].y - dp[1] * duv[0].y) / det;
}

/// Traces 600 rays (fixed seed) from a sphere of radius 4 extent around `centre` toward points
/// within `extent` of it; at every usable hit (not grazing, `usable` agrees), dpdu must be
/// nonzero, tangent (|dpdu . ng| <= 1e-4 |dpdu|: both are floats computed from the same
/// data, so they meet rounding, ~1e-7, not 1e-4), and agree with the finite differences at
/// step 1e-2 extent. Central differences are exact for the triangles' linear
/// parameterization and err by O((h / R)^2) ~ 1e-4 relative on the curved ones (curvature
/// radius R >= 0.7 extent here); float rounding adds ~1e-7 |p| / 2h ~ 1e-5 through the chords
/// and ~6e-8 / |du| ~ 3e-5 through the uvs, times the uv system's condition (< 10 here). Hence
/// 2e-3 |dpdu| (the largest error seen: 6e-4, on the sphere near |cos theta| = 0.9; 5e-5 on
/// the meshes). Returns the number of hits checked.
int expect_dpdu_matches_finite_differences(
    const Scene& scene, const Vec3& centre, float extent,
    const std::function<bool(const Hit&)>& usable = [](const Hit&) { return true; }) {
    std::mt19937 rng(2024);
    std::uniform_real_distribution<float> uni(0.f, 1.f);
    auto unit = [&] {
        const float z = 2 * uni(rng) - 1, phi = 2 * femto::kPi * uni(rng);
        const float r = std::sqrt(1 - z * z);
        return Vec3(r * std::cos(phi), r * std::sin(phi), z);
    };
    int checked = 0;
    for (int i = 0; i < 600; ++i) {
        const Vec3 from = centre + unit() * (4 * extent);
        const Vec3 aim = centre + unit() * (extent * uni(rng));
        const Vec3 d = normalize(aim - from);
        Hit hit;
        if (!scene.intersect(Ray{from, d, 0.f, femto::kInfinity}, hit)) continue;
        if (std::abs(dot(d, hit.ng)) < 0.25f || !usable(hit)) continue;
        const float len = length(hit.dpdu);
        if (!(len > 0 && std::isfinite(len))) {
            ADD_FAILURE() << "dpdu is zero or not finite at hit " << i;
            continue;
        }
        EXPECT_LE(std::abs(dot(hit.dpdu, hit.ng)), 1e-4f * len) << "at hit " << i;
        const auto estimate = finite_difference_dpdu(scene, from, hit, 1e-2f * extent);
        if (!estimate) continue;
        ++checked;
        EXPECT_TRUE(vec_near(hit.dpdu, *estimate, 2e-3 * len)) << "at hit " << i;
    }
    return checked;
}

TEST(HitTangent, MeshWithUvsMatchesFiniteDifferences) {
    ScratchDir dir;
    // Mitsuba's v flip (v -> 1 - v) does not touch u, so it is left on.
    const auto scene = load(obj_shape(dir.write("pyramid.obj", kPyramidWithUvs)));
    EXPECT_GE(expect_dpdu_matches_finite_differences(*scene, kPyramidCentre, 1.f), 300);
}

TEST(HitTangent, MeshWithoutUvsIsTheFirstEdge) {
    ScratchDir dir;
    const auto scene = load(obj_shape(dir.write("pyramid.obj", kPyramidWithoutUvs)));
    EXPECT_GE(expect_dpdu_matches_finite_differences(*scene, kPyramidCentre, 1.f), 300);
    // uv is Embree's barycentric (u, v) of p = (1-u-v) p0 + u p1 + v p2: dp/du is p1 - p0.
    Hit hit;
    ASSERT_TRUE(scene->intersect(Ray{{1.1f, 0.2f, 3.f}, {0, 0, -1}, 0.f, femto::kInfinity}, hit));
    const femto::TriangleMesh& m = hit.shape->mesh();
    ASSERT_TRUE(m.uvs.empty());
    EXPECT_EQ(hit.dpdu,
              m.positions[m.indices[3 * hit.prim + 1]] - m.positions[m.indices[3 * hit.prim]]);
}

TEST(HitTangent, RectangleIsAlongX) {
    // The rectangle's u = (x + 1) / 2: dp/du = (2, 0, 0), then scaled and rotated by to_world.
    const auto scene = load(
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale x=\"3\" y=\"0.5\"/>"
        "<rotate z=\"1\" angle=\"90\"/></transform>" +
        tangent_bsdf() + "</shape>");
    Hit hit;
    ASSERT_TRUE(scene->intersect(Ray{{0.1f, 0.4f, 2.f}, {0, 0, -1}, 0.f, femto::kInfinity}, hit));
    EXPECT_TRUE(vec_near(hit.dpdu, {0, 6, 0}, 1e-5));
}

TEST(HitTangent, SphereMatchesFiniteDifferencesAwayFromThePoles) {
    const auto scene = load(sphere_shape());
    // Near the poles u changes fast and |dpdu| = 2 pi r sin(theta) vanishes: stay within
    // |cos theta| <= 0.9 (uv follows the world's axes, whatever the rotation).
    const int checked =
        expect_dpdu_matches_finite_differences(*scene, {0, 0, 0}, 1.f, [&](const Hit& hit) {
            const Vec3 local = normalize(hit.p - hit.shape->sphere_center());
            return std::abs(local.z) <= 0.9f;
        });
    EXPECT_GE(checked, 300);
}

TEST(HitTangent, SpherePolesGiveZero) {
    const auto sphere = make_shape([] {
        Properties props("sphere", {});
        props.set_point("center", Vec3(0.3f, -0.2f, 0.1f));
        props.set_float("radius", 0.8);
        return props;
    }());
    ASSERT_TRUE(sphere);
    const Vec3 c = sphere->sphere_center();
    const float r = sphere->sphere_radius();
    for (const float side : {1.f, -1.f}) {
        Hit hit;
        ASSERT_TRUE(brute_intersect(
            *sphere, Ray{c + Vec3(0, 0, 3 * r * side), {0, 0, -side}, 0.f, femto::kInfinity}, hit));
        // phi is undefined there: dpdu is zero up to the rounding of p (or at least tangent).
        EXPECT_LE(length(hit.dpdu), 1e-5f * 2 * femto::kPi * r) << "side " << side;
        EXPECT_LE(std::abs(dot(hit.dpdu, hit.ng)), 1e-6f) << "side " << side;
    }
}

TEST(HitTangent, CylinderMatchesFiniteDifferences) {
    const auto scene = load(cylinder_shape());
    EXPECT_GE(expect_dpdu_matches_finite_differences(*scene, {-0.05f, 0.15f, 0.25f}, 1.f), 300);
}

TEST(HitTangent, InstanceMovesDpduAsAVector) {
    ScratchDir dir;
    const auto scene =
        load("<shape type=\"shapegroup\" id=\"g\">" +
             obj_shape(dir.write("pyramid.obj", kPyramidWithUvs)) +
             "</shape><shape type=\"instance\"><ref id=\"g\"/><transform name=\"to_world\">"
             "<scale x=\"1.5\" y=\"0.7\" z=\"1.2\"/><rotate x=\"1\" y=\"2\" z=\"0.5\" "
             "angle=\"50\"/><translate x=\"0.4\" y=\"-0.3\" z=\"0.2\"/></transform></shape>");
    // The pyramid's centre, placed by the instance (scale, then rotation, then translation).
    const femto::Transform to_world = femto::Transform::translate({0.4f, -0.3f, 0.2f}) *
                                      femto::Transform::rotate({1, 2, 0.5f}, 50.f) *
                                      femto::Transform::scale({1.5f, 0.7f, 1.2f});
    EXPECT_GE(expect_dpdu_matches_finite_differences(*scene, to_world.point(kPyramidCentre), 1.2f),
              300);
}

/// Hits of the same rays on a shape written with and without flip_normals: the same dpdu, the
/// opposite geometric normal.
void expect_flip_keeps_dpdu(const std::string& plain, const std::string& flipped,
                            const Vec3& centre) {
    const auto a = load(plain), b = load(flipped);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> uni(-1.f, 1.f);
    int hits = 0;
    for (int i = 0; i < 200; ++i) {
        const Vec3 from = centre + Vec3(4 * uni(rng), 4 * uni(rng), 4.f);
        const Vec3 aim = centre + Vec3(uni(rng), uni(rng), uni(rng)) * 0.5f;
        const Ray ray{from, normalize(aim - from), 0.f, femto::kInfinity};
        Hit ha, hb;
        const bool found = a->intersect(ray, ha);
        ASSERT_EQ(found, b->intersect(ray, hb));
        if (!found) continue;
        ++hits;
        EXPECT_EQ(ha.dpdu, hb.dpdu);
        EXPECT_EQ(ha.ng, -hb.ng);
    }
    EXPECT_GE(hits, 100);
}

TEST(HitTangent, FlipNormalsLeavesDpduUnchanged) {
    ScratchDir dir;
    const std::string file = dir.write("pyramid.obj", kPyramidWithUvs);
    const std::string flip = "<boolean name=\"flip_normals\" value=\"true\"/>";
    {
        SCOPED_TRACE("mesh");
        expect_flip_keeps_dpdu(obj_shape(file), obj_shape(file, flip), kPyramidCentre);
    }
    {
        SCOPED_TRACE("sphere");
        expect_flip_keeps_dpdu(sphere_shape(), sphere_shape(flip), {0, 0, 0});
    }
    {
        SCOPED_TRACE("cylinder");
        expect_flip_keeps_dpdu(cylinder_shape(), cylinder_shape(flip), {-0.05f, 0.15f, 0.25f});
    }
}

/// The hit straight down onto a single triangle (0,0,0) (1,0,0) (0,1,0) whose vertices carry
/// `uvs` (an obj file's vt lines, not flipped).
Hit hit_on_triangle_with_uvs(const ScratchDir& dir, const std::string& uvs) {
    Properties props("obj", {});
    props.set_string("filename", dir.write("triangle.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n" + uvs +
                                                               "f 1/1 2/2 3/3\n"));
    props.set_bool("flip_tex_coords", false);
    Properties btf("btf", {});  // a material that reads the tangent (Bsdf::uses_tangent())
    btf.set_string("filename",
                   femto::test::write_btf(femto::test::small_btf_a(), "hit_tangent", "a.dfmf"));
    props.set_object("bsdf", femto::create_object(femto::PluginKind::Bsdf, "btf", btf));
    const auto shape = make_shape(props);
    Hit hit;
    if (!shape ||
        !brute_intersect(*shape, Ray{{0.2f, 0.3f, 1.f}, {0, 0, -1}, 0.f, femto::kInfinity}, hit))
        ADD_FAILURE() << "no hit";
    return hit;
}

TEST(HitTangent, DegenerateTriangleUvsGiveZero) {
    ScratchDir dir;
    EXPECT_EQ(hit_on_triangle_with_uvs(dir, "vt 0 0\nvt 0.5 0.5\nvt 1 1\n").dpdu, Vec3(0.f));
    EXPECT_EQ(hit_on_triangle_with_uvs(dir, "vt 0.3 0.3\nvt 0.3 0.3\nvt 0.3 0.3\n").dpdu,
              Vec3(0.f));
    // Tiny but well-shaped uvs are not degenerate: the threshold is relative to the uv edges.
    EXPECT_TRUE(vec_near(hit_on_triangle_with_uvs(dir, "vt 0 0\nvt 1e-4 0\nvt 0 1e-4\n").dpdu,
                         {1e4f, 0, 0}, 1.0));
    // Large, offset uvs: u = 1000 + 2x, v = 500 + 3y gives dp/du = (1/2, 0, 0).
    EXPECT_TRUE(
        vec_near(hit_on_triangle_with_uvs(dir, "vt 1000 500\nvt 1002 500\nvt 1000 503\n").dpdu,
                 {0.5f, 0, 0}, 1e-6));
}

TEST(HitTangent, OnlyMaterialsThatReadItGetIt) {
    // The same rectangle under a BTF (uses_tangent()), the BTF inside twosided and mask (which
    // pass the question on), and a diffuse material, which does not read the tangent: its hits
    // skip the solve unless the ray carries a differential (a footprint needs dpdu).
    const std::string rect =
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale "
        "x=\"3\" y=\"0.5\"/></transform>";
    const Ray down{{0.1f, 0.2f, 2.f}, {0, 0, -1}, 0.f, femto::kInfinity};
    const Vec3 expected{6, 0, 0};
    for (const std::string& bsdf :
         {tangent_bsdf(), "<bsdf type=\"twosided\">" + tangent_bsdf() + "</bsdf>",
          "<bsdf type=\"mask\"><float name=\"opacity\" value=\"0.5\"/>" + tangent_bsdf() +
              "</bsdf>"}) {
        const auto scene = load(rect + bsdf + "</shape>");
        Hit hit;
        ASSERT_TRUE(scene->intersect(down, hit));
        EXPECT_TRUE(vec_near(hit.dpdu, expected, 1e-5)) << bsdf;
    }
    const auto diffuse = load(rect + "</shape>");
    Hit hit;
    ASSERT_TRUE(diffuse->intersect(down, hit));
    EXPECT_EQ(hit.dpdu, Vec3(0.f));
    femto::RayDifferential differential{down.o + Vec3(1e-3f, 0, 0), down.d, down.o,
                                        normalize(down.d + Vec3(0, 1e-3f, 0))};
    Ray with_differential = down;
    with_differential.differential = &differential;
    ASSERT_TRUE(diffuse->intersect(with_differential, hit));
    EXPECT_TRUE(vec_near(hit.dpdu, expected, 1e-5));
    EXPECT_TRUE(hit.footprint.valid);
}

}  // namespace
