// The analytic `cylinder` shape (Mitsuba 0.6 and 3): intersection against closed forms, uniform
// area sampling (chi-square), an emitting tube's power, a render against a tessellated tube,
// and located errors for bad parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "agreement_util.h"
#include "chi2.h"
#include "femto/emitter.h"
#include "femto/error.h"
#include "femto/random.h"
#include "femto/scene.h"
#include "femto/shape.h"
#include "femto/transform.h"
#include "femto/warp.h"
#include "scene_util.h"
#include "shape_test_util.h"

namespace {

using femto::Color;
using femto::Emitter;
using femto::EmitterSample;
using femto::Hit;
using femto::Properties;
using femto::Ray;
using femto::Shape;
using femto::Transform;
using femto::Vec2;
using femto::Vec3;
using femto_shape_test::brute_intersect;
using femto_shape_test::make_emitter;
using femto_shape_test::make_shape;
using femto_shape_test::vec_near;

constexpr double kPiD = 3.14159265358979323846;

std::string error_of(const Properties& props) {
    try {
        make_shape(props);
    } catch (const femto::SceneError& e) {
        return e.what();
    }
    return "(no error)";
}

::testing::AssertionResult color_near(const Color& a, const Color& b, double rel) {
    for (int k = 0; k < 3; ++k)
        if (!(std::abs(double(a[k]) - double(b[k])) <= rel * std::abs(double(b[k]))))
            return ::testing::AssertionFailure()
                   << "colour channel " << k << ": " << a[k] << " vs " << b[k];
    return ::testing::AssertionSuccess();
}

bool contains(const std::string& s, const std::string& part) {
    return s.find(part) != std::string::npos;
}

TEST(ShapeCylinder, DefaultsFollowMitsuba) {
    auto s = make_shape(Properties("cylinder", {}));
    ASSERT_TRUE(s);
    EXPECT_TRUE(s->is_cylinder());
    EXPECT_FALSE(s->is_sphere());
    EXPECT_TRUE(vec_near(s->cylinder_base(), Vec3(0.f), 0));
    EXPECT_TRUE(vec_near(s->cylinder_frame().n, {0, 0, 1}, 0));
    // Mitsuba's frame of +z: phi = 0 along +x, pi/2 along +y.
    EXPECT_TRUE(vec_near(s->cylinder_frame().s, {1, 0, 0}, 0));
    EXPECT_TRUE(vec_near(s->cylinder_frame().t, {0, 1, 0}, 0));
    EXPECT_EQ(s->cylinder_radius(), 1.f);
    EXPECT_EQ(s->cylinder_length(), 1.f);
    EXPECT_NEAR(s->surface_area(), 2 * kPiD, 2 * kPiD * 1e-6);
}

TEST(ShapeCylinder, EndpointsRadiusAndToWorld) {
    // p0 -> p1 along y, radius 0.5, then scaled by 2 and moved: radius 1, length 4.
    Properties props("cylinder", {});
    props.set_point("p0", {1, 0, 0});
    props.set_point("p1", {1, 2, 0});
    props.set_float("radius", 0.5);
    props.set_transform("to_world", Transform::translate({0, 0, 3}) * Transform::scale({2, 2, 2}));
    auto s = make_shape(props);
    ASSERT_TRUE(s);
    EXPECT_TRUE(vec_near(s->cylinder_base(), {2, 0, 3}, 1e-6));
    EXPECT_TRUE(vec_near(s->cylinder_frame().n, {0, 1, 0}, 1e-6));
    EXPECT_NEAR(s->cylinder_radius(), 1.f, 1e-6);
    EXPECT_NEAR(s->cylinder_length(), 4.f, 1e-6);
    EXPECT_NEAR(s->surface_area(), 8 * kPiD, 8 * kPiD * 1e-6);

    // A scale along the axis only changes the length (Mitsuba's own to_world is one).
    Properties along("cylinder", {});
    along.set_transform("to_world", Transform::rotate({1, 0, 0}, 90) * Transform::scale({3, 3, 5}));
    auto a = make_shape(along);
    ASSERT_TRUE(a);
    EXPECT_NEAR(a->cylinder_radius(), 3.f, 1e-6);
    EXPECT_NEAR(a->cylinder_length(), 5.f, 1e-6);
    EXPECT_TRUE(vec_near(a->cylinder_frame().n, {0, -1, 0}, 1e-6));
}

/// The closed form for a tube of radius R along z from 0 to L, hit by rays in the plane
/// z = z0 along +x at height y (|y| < R) from x0 < -R: the near hit at x = -sqrt(R^2 - y^2),
/// outward normal (x, y, 0) / R, uv = (phi / 2pi, z0 / L). Every ray and point is then moved
/// by a rigid `to_world` given to the shape as well.
TEST(ShapeCylinder, IntersectionMatchesClosedForm) {
    const double R = 0.75, L = 2;
    const Transform to_world = Transform::translate({0.5f, -1, 2}) *
                               Transform::rotate({1, 2, 3}, 37) * Transform::rotate({0, 0, 1}, 0);
    Properties props("cylinder", {});
    props.set_float("radius", R);
    props.set_point("p1", {0, 0, float(L)});
    props.set_transform("to_world", to_world);
    auto s = make_shape(props);
    ASSERT_TRUE(s);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> uy(-0.99 * R, 0.99 * R), uz(0.01 * L, 0.99 * L);
    for (int i = 0; i < 200; ++i) {
        const double y = uy(rng), z = uz(rng), x0 = -3;
        const double x = -std::sqrt(R * R - y * y);
        const Vec3 o = to_world.point(Vec3(float(x0), float(y), float(z)));
        const Vec3 d = femto::normalize(to_world.vector({1, 0, 0}));
        Hit hit;
        ASSERT_TRUE(brute_intersect(*s, Ray{o, d, 0.f, femto::kInfinity}, hit)) << i;
        EXPECT_NEAR(hit.t, x - x0, 2e-5) << i;
        EXPECT_TRUE(vec_near(hit.p, to_world.point(Vec3(float(x), float(y), float(z))), 2e-5));
        const Vec3 n = femto::normalize(to_world.vector(Vec3(float(x / R), float(y / R), 0)));
        EXPECT_TRUE(vec_near(hit.ng, n, 1e-5)) << i;
        EXPECT_TRUE(vec_near(hit.sh.n, n, 1e-5)) << i;
        double phi = std::atan2(y, x);
        if (phi < 0) phi += 2 * kPiD;
        EXPECT_NEAR(hit.uv.x, phi / (2 * kPiD), 1e-5) << i;
        EXPECT_NEAR(hit.uv.y, z / L, 1e-5) << i;

        // From inside the tube the far side is hit; the normal still points away from the
        // axis (toward the ray's origin's back), and flip_normals turns it.
        const Vec3 inside = to_world.point(Vec3(0, float(y), float(z)));
        ASSERT_TRUE(brute_intersect(*s, Ray{inside, d, 0.f, femto::kInfinity}, hit));
        EXPECT_NEAR(hit.t, -x, 2e-5);
        const Vec3 n_far = femto::normalize(to_world.vector(Vec3(float(-x / R), float(y / R), 0)));
        EXPECT_TRUE(vec_near(hit.ng, n_far, 1e-5)) << i;
        EXPECT_GT(femto::dot(hit.ng, d), 0.f);

        // Past either end: no caps, so a ray above the tube misses, and one that enters
        // through the open end hits the inside.
        const Vec3 above = to_world.point(Vec3(float(x0), float(y), float(L + 0.1)));
        EXPECT_FALSE(brute_intersect(*s, Ray{above, d, 0.f, femto::kInfinity}, hit));
    }
    // A ray down the open end at a slant meets the inner wall at the closed-form point.
    const Vec3 top = to_world.point(Vec3(0, 0, float(L + 1)));
    const Vec3 slant = femto::normalize(to_world.vector(Vec3(float(R), 0, -2)));
    Hit hit;
    ASSERT_TRUE(brute_intersect(*s, Ray{top, slant, 0.f, femto::kInfinity}, hit));
    // It reaches x = R after t = |(R, 0, -2)|, at z = L + 1 - 2 = L - 1.
    EXPECT_NEAR(hit.t, std::sqrt(R * R + 4), 2e-5);
    EXPECT_TRUE(vec_near(hit.p, to_world.point(Vec3(float(R), 0, float(L - 1))), 2e-5));
    // A ray along the axis never meets the wall; one inside the [tmin, tmax] window only.
    EXPECT_FALSE(brute_intersect(
        *s, Ray{top, femto::normalize(to_world.vector({0, 0, -1})), 0.f, femto::kInfinity}, hit));
    const Vec3 o = to_world.point(Vec3(-3, 0, 1));
    const Vec3 d = femto::normalize(to_world.vector({1, 0, 0}));
    EXPECT_FALSE(brute_intersect(*s, Ray{o, d, 0.f, float(3 - R - 1e-3)}, hit));
    ASSERT_TRUE(brute_intersect(*s, Ray{o, d, float(3 - R + 1e-3), femto::kInfinity}, hit));
    EXPECT_NEAR(hit.t, 3 + R, 2e-5);
}

// The Embree scene traces cylinders (user geometry) as the shape's own routine does, and
// shadow rays are blocked by them.
TEST(ShapeCylinder, SceneTracesTheCylinder) {
    const std::string xml = femto::test::scene_xml(
        "<shape type=\"cylinder\"><point name=\"p0\" x=\"0\" y=\"0\" z=\"-1\"/>"
        "<point name=\"p1\" x=\"0\" y=\"0\" z=\"1\"/><float name=\"radius\" value=\"0.5\"/>"
        "<transform name=\"to_world\"><translate x=\"1\"/></transform></shape>");
    auto scene = femto::load_scene_string(xml);
    Hit hit;
    ASSERT_TRUE(scene->intersect(Ray{{-3, 0, 0.25f}, {1, 0, 0}, 0.f, femto::kInfinity}, hit));
    EXPECT_NEAR(hit.t, 3.5f, 1e-5);
    EXPECT_TRUE(vec_near(hit.ng, {-1, 0, 0}, 1e-6));
    EXPECT_NEAR(hit.uv.y, 0.625f, 1e-6);
    // The next hit from there is the inside of the far wall.
    Hit far;
    ASSERT_TRUE(scene->intersect(hit.spawn({1, 0, 0}), far));
    EXPECT_NEAR(far.p.x, 1.5f, 1e-5);
    EXPECT_TRUE(scene->occluded(Ray{{-3, 0, 0}, {1, 0, 0}, 0.f, 10.f}));
    EXPECT_FALSE(scene->occluded(Ray{{-3, 0, 0}, {1, 0, 0}, 0.f, 3.f}));
    EXPECT_FALSE(scene->occluded(Ray{{-3, 0, 1.5f}, {1, 0, 0}, 0.f, 10.f}));
    EXPECT_FALSE(scene->intersect(Ray{{1, 0, -3}, {0, 0, 1}, 0.f, femto::kInfinity}, hit));
    EXPECT_GE(scene->bounds().max.z, 1.f);
    EXPECT_LE(scene->bounds().min.x, 0.5f);
}

// Rays leaving the tube (docs/precision.md) at sizes 1e-6 ... 1e6, at the origin and 1e3 sizes
// away from it: outward rays find nothing (the outside is convex), inward rays find the far
// wall or leave through an open end, never the point they left: a hit is at least half the
// exact chord 2 r (-in . n) / (1 - (in . a)^2) away.
TEST(ShapeCylinder, RaysLeavingItNeverHitItAgainAtAnyScale) {
    const Vec3 axis = femto::normalize(Vec3(1, 2, 3));
    femto_shape_test::for_each_scale([&](double size, const Vec3& c) {
        const Vec3 p0 = c - axis * float(size), p1 = c + axis * float(size);
        auto point = [](const char* name, const Vec3& p) {
            return "<point name=\"" + std::string(name) + "\" x=\"" + femto::test::xml_number(p.x) +
                   "\" y=\"" + femto::test::xml_number(p.y) + "\" z=\"" +
                   femto::test::xml_number(p.z) + "\"/>";
        };
        auto scene = femto::load_scene_string(femto::test::scene_xml(
            "<shape type=\"cylinder\">" + point("p0", p0) + point("p1", p1) +
            "<float name=\"radius\" value=\"" + femto::test::xml_number(size) + "\"/></shape>"));
        // Inward rays find the far wall (or leave through an open end), never closer than half
        // the exact chord.
        int far_walls = 0;
        const int hits = femto_shape_test::expect_rays_leave(
            *scene, c, size, [&](const Hit& hit, const Hit* again, const Vec3& in) {
                if (!again) return false;
                ++far_walls;
                const double along = femto::dot(in, axis);
                const double chord = 2 * size * -femto::dot(in, hit.ng) / (1 - along * along);
                return femto::distance_between(hit.p, again->p) < 0.5 * chord;
            });
        EXPECT_GT(hits, 200);
        EXPECT_GT(far_walls, hits / 4);
    });
}

// sample_area is uniform over the surface: (phi / 2pi, z / L) recovered from the sampled point
// is uniform on the unit square (chi-square), the point lies on the tube, the normal is
// radial (inward with flip_normals) and the pdf is 1 / area.
TEST(ShapeCylinder, AreaSamplingIsUniform) {
    const double R = 0.4, L = 1.5;
    const Transform to_world = Transform::translate({1, 2, 3}) * Transform::rotate({2, -1, 1}, 60);
    for (const bool flip : {false, true}) {
        Properties props("cylinder", {});
        props.set_float("radius", R);
        props.set_point("p1", {0, 0, float(L)});
        props.set_bool("flip_normals", flip);
        props.set_transform("to_world", to_world);
        auto s = make_shape(props);
        ASSERT_TRUE(s);
        const Transform to_local = to_world.inverse();
        femto_test::Chi2Options o;
        o.nx = o.ny = 16;
        o.x0 = o.y0 = 0;
        o.x1 = o.y1 = 1;
        o.samples = 200000;
        o.seed = femto_test::seed_from_name(std::string("cylinder area") + (flip ? " flip" : ""));
        int checked = 0;
        const auto res = femto_test::chi2_test(
            o,
            [&](femto::Pcg32& rng) -> std::optional<std::pair<double, double>> {
                const femto::ShapeSample ss = s->sample_area({rng.next_float(), rng.next_float()});
                const Vec3 q = to_local.point(ss.p);
                if (checked++ < 1000) {
                    EXPECT_NEAR(std::hypot(q.x, q.y), R, 1e-5);
                    const Vec3 radial = femto::normalize(to_world.vector({q.x, q.y, 0}));
                    EXPECT_TRUE(vec_near(ss.n, flip ? -radial : radial, 1e-5));
                    EXPECT_NEAR(ss.pdf * s->surface_area(), 1.f, 1e-6);
                }
                double phi = std::atan2(double(q.y), double(q.x));
                if (phi < 0) phi += 2 * kPiD;
                return std::make_pair(phi / (2 * kPiD), double(q.z) / L);
            },
            [](double, double) { return 1.0; });
        EXPECT_TRUE(res.error.empty()) << res.describe();
        EXPECT_GT(res.p_value, femto_test::corrected_significance(2)) << res.describe();
        EXPECT_NEAR(s->surface_area(), 2 * kPiD * R * L, 2 * kPiD * R * L * 1e-6);
    }
}

struct Lit {
    std::shared_ptr<Shape> shape;
    std::shared_ptr<Emitter> emitter;
};

Lit emitting_tube(double R, double L, const Color& radiance) {
    Properties sp("cylinder", {});
    sp.set_float("radius", R);
    sp.set_point("p0", {0, 0, float(-L / 2)});
    sp.set_point("p1", {0, 0, float(L / 2)});
    sp.set_transform("to_world",
                     Transform::translate({0.2f, -0.1f, 0.3f}) * Transform::rotate({1, 1, 0}, 25));
    Properties ep("area", {});
    ep.set_color("radiance", radiance);
    Lit lit{make_shape(sp), make_emitter(ep)};
    if (lit.shape && lit.emitter) lit.emitter->set_shape(lit.shape.get());
    return lit;
}

// Direct sampling of an emitting tube: the pdf of a sample equals pdf_direct of the hit a ray
// finds there, and the weight is radiance / pdf. Points on the far side face away (one-sided
// emission) and have pdf 0.
TEST(ShapeCylinder, EmitterSampleAndPdfAreConsistent) {
    const Color radiance(1, 2, 3);
    const Lit lit = emitting_tube(0.5, 2, radiance);
    ASSERT_TRUE(lit.shape && lit.emitter);
    const Vec3 ref(2.5f, 1.f, 0.2f);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> uni(0.f, 1.f);
    int front = 0;
    for (int i = 0; i < 400; ++i) {
        const EmitterSample s = lit.emitter->sample_direct(ref, {uni(rng), uni(rng)});
        if (s.pdf == 0) continue;
        ++front;
        EXPECT_TRUE(color_near(s.weight * s.pdf, radiance, 1e-6));
        EXPECT_LT(femto::dot(s.wi, s.n), 0.f);
        Hit hit;
        ASSERT_TRUE(brute_intersect(*lit.shape, femto_shape_test::ray_toward(ref, s.p), hit));
        EXPECT_TRUE(vec_near(hit.p, s.p, 1e-4));
        // The cosine at the light can be small near the silhouette: compare relative to it.
        const float cos = std::abs(femto::dot(hit.ng, s.wi));
        if (cos > 0.05f) {
            EXPECT_NEAR(lit.emitter->pdf_direct(ref, hit), s.pdf, 2e-4 * s.pdf / cos);
        }
    }
    // Seen from outside, a little under half of the tube faces the point.
    EXPECT_GT(front, 120);
    EXPECT_LT(front, 200);
}

// Radiant power of an emitting tube: Phi = pi L_e A = 2 pi^2 L_e R l (the outside emits, and
// as the outer surface is convex none of it returns to the tube). Measured as the flux
// through a large sphere S around it: Phi = |S| E[E(x)] for x uniform on S, where E(x) is the
// irradiance at x on S's inner side estimated from one sample_direct each.
TEST(ShapeCylinder, EmittingTubeRadiatesClosedFormPower) {
    const double R = 0.3, L = 1.2, Le = 2, Rs = 4;
    const Lit lit = emitting_tube(R, L, Color(float(Le)));
    ASSERT_TRUE(lit.shape && lit.emitter);
    femto::Pcg32 rng(17, 3);
    const int n = 400000;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        const Vec3 dir =
            femto::warp::square_to_uniform_sphere({rng.next_float(), rng.next_float()});
        const Vec3 x = dir * float(Rs);
        const EmitterSample s = lit.emitter->sample_direct(x, {rng.next_float(), rng.next_float()});
        const double e = s.pdf > 0 ? double(s.weight.r) * std::max(0.f, -femto::dot(s.wi, dir)) : 0;
        sum += e, sum2 += e * e;
    }
    const double area_s = 4 * kPiD * Rs * Rs;
    const double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1));
    const double expected = 2 * kPiD * kPiD * Le * R * L;
    std::printf("tube power %.5f +- %.5f, closed form %.5f\n", area_s * mean, area_s * se,
                expected);
    EXPECT_NEAR(area_s * mean, expected, 5 * area_s * se);
    EXPECT_LT(area_s * se, 0.01 * expected);
}

// -- a render against a tessellated tube ------------------------------------------------------

/// An OBJ of the same open tube (radius 1, z from 0 to 1: the cylinder's object space) with
/// `segments` quads around, outward vertex normals and Mitsuba's uv.
std::string tube_obj(int segments) {
    std::string obj;
    char line[128];
    for (int k = 0; k <= segments; ++k) {
        const double phi = 2 * kPiD * k / segments;
        for (int z = 0; z < 2; ++z) {
            std::snprintf(line, sizeof line, "v %.9f %.9f %d\nvn %.9f %.9f 0\nvt %.9f %d\n",
                          std::cos(phi), std::sin(phi), z, std::cos(phi), std::sin(phi),
                          double(k) / segments, z);
            obj += line;
        }
    }
    for (int k = 0; k < segments; ++k) {
        const int a = 2 * k + 1, b = a + 1, c = a + 2, d = a + 3;  // a, c bottom; b, d top
        std::snprintf(line, sizeof line,
                      "f %d/%d/%d %d/%d/%d %d/%d/%d\nf %d/%d/%d %d/%d/%d %d/%d/%d\n", a, a, a, c, c,
                      c, b, b, b, b, b, b, c, c, c, d, d, d);
        obj += line;
    }
    return obj;
}

std::string tube_scene(const std::string& shape) {
    return "<scene version=\"3.0.0\">"
           "<integrator type=\"path\"><integer name=\"max_depth\" value=\"3\"/></integrator>"
           "<sensor type=\"perspective\"><float name=\"fov\" value=\"40\"/>"
           "<transform name=\"to_world\"><lookat origin=\"0, -4, 2.5\" target=\"0, 0, 0.3\" "
           "up=\"0, 0, 1\"/></transform>"
           "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"16\"/></sampler>"
           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"24\"/>"
           "<integer name=\"height\" value=\"24\"/><rfilter type=\"box\"/></film></sensor>"
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/>"
           "<translate z=\"-0.5\"/></transform></shape>"
           "<shape type=\"rectangle\"><transform name=\"to_world\"><rotate x=\"1\" angle=\"180\"/>"
           "<translate x=\"1\" y=\"-1\" z=\"3\"/></transform>"
           "<emitter type=\"area\"><rgb name=\"radiance\" value=\"3\"/></emitter></shape>" +
           shape + "</scene>";
}

// The tube's place: radius 0.6, from z = -0.5 to 1 (p0, p1, radius) or the unit tube scaled.
const char* kTubeBody =
    "<bsdf type=\"twosided\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
    "value=\"0.7, 0.5, 0.3\"/></bsdf></bsdf></shape>";

TEST(ShapeCylinder, RendersAsATessellatedTube) {
    const auto dir = femto::testing::temp_dir("cylinder-mesh");
    femto::test::write_text(dir / "tube.obj", tube_obj(512));
    const std::string analytic = tube_scene(
        "<shape type=\"cylinder\"><point name=\"p0\" x=\"0\" y=\"0\" z=\"-0.5\"/>"
        "<point name=\"p1\" x=\"0\" y=\"0\" z=\"1\"/><float name=\"radius\" value=\"0.6\"/>" +
        std::string(kTubeBody));
    const std::string mesh = tube_scene(
        "<shape type=\"obj\"><string name=\"filename\" value=\"tube.obj\"/>"
        "<transform name=\"to_world\"><scale x=\"0.6\" y=\"0.6\" z=\"1.5\"/>"
        "<translate z=\"-0.5\"/></transform>" +
        std::string(kTubeBody));
    constexpr int kRuns = 16;
    auto runs = [&](const std::string& xml, uint64_t seed) {
        std::vector<femto::testing::Cube> out;
        for (int r = 0; r < kRuns; ++r) {
            auto scene = femto::load_scene_string(xml, {}, dir.string());
            const std::vector<float> img = femto::testing::render_steady(*scene, seed + r);
            femto::testing::Cube c;
            c.H = c.W = 24, c.T = 1, c.C = 3;
            c.data = img;
            out.push_back(std::move(c));
        }
        return out;
    };
    const auto a = runs(analytic, 10), b = runs(mesh, 50);
    femto::test::expect_agree(femto::test::cells_of(a, 1, 1), femto::test::cells_of(b, 1, 1), kRuns,
                              "cylinder vs tessellated tube");
}

// An emitting tube lighting a floor: the path tracer (emitter sampling and hits weighed by
// MIS, through pdf_direct of a hit on the tube) and the light tracer (emission sampled on the
// tube) render the same image to noise.
TEST(ShapeCylinder, EmittingTubeRendersAlikeForPathAndLightTracers) {
    auto xml = [](const std::string& integrator) {
        return "<scene version=\"3.0.0\"><integrator type=\"" + integrator +
               "\"><integer name=\"max_depth\" value=\"3\"/><boolean name=\"hide_emitters\" "
               "value=\"true\"/></integrator><sensor type=\"perspective\"><float name=\"fov\" "
               "value=\"45\"/><transform name=\"to_world\"><lookat origin=\"0, -4, 3\" "
               "target=\"0, 0, 0\" up=\"0, 0, 1\"/></transform><sampler "
               "type=\"independent\"><integer name=\"sample_count\" value=\"16\"/></sampler>"
               "<film type=\"hdrfilm\"><integer name=\"width\" value=\"24\"/><integer "
               "name=\"height\" value=\"24\"/><rfilter type=\"box\"/></film></sensor>"
               "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/>"
               "</transform></shape><shape type=\"cylinder\"><point name=\"p0\" x=\"-1\" "
               "y=\"0.3\" z=\"0.6\"/><point name=\"p1\" x=\"1\" y=\"-0.2\" z=\"0.8\"/><float "
               "name=\"radius\" value=\"0.2\"/><emitter type=\"area\"><rgb name=\"radiance\" "
               "value=\"2\"/></emitter></shape></scene>";
    };
    constexpr int kRuns = 16;
    auto runs = [&](const std::string& scene_xml, uint64_t seed) {
        std::vector<femto::testing::Cube> out;
        for (int r = 0; r < kRuns; ++r) {
            auto scene = femto::load_scene_string(scene_xml);
            femto::testing::Cube c;
            c.H = c.W = 24, c.T = 1, c.C = 3;
            c.data = femto::testing::render_steady(*scene, seed + uint64_t(r));
            out.push_back(std::move(c));
        }
        return out;
    };
    femto::test::expect_agree(femto::test::cells_of(runs(xml("transient_light"), 1), 1, 1),
                              femto::test::cells_of(runs(xml("path"), 101), 1, 1), kRuns,
                              "emitting tube: light tracer vs path tracer");
}

// -- bad input --------------------------------------------------------------------------------

TEST(ShapeCylinder, BadParametersAreLocatedErrors) {
    for (const char* r : {"0", "-1", "nan"}) {
        const std::string msg = femto::test::load_error(
            femto::test::scene_xml("<shape type=\"cylinder\">\n  <float name=\"radius\" value=\"" +
                                   std::string(r) + "\"/></shape>"));
        EXPECT_TRUE(contains(msg, "<string>:4:3")) << msg;
        EXPECT_TRUE(contains(msg, "radius")) << msg;
    }
    std::string msg = femto::test::load_error(femto::test::scene_xml(
        "<shape type=\"cylinder\">\n<point name=\"p0\" x=\"1\" y=\"1\" z=\"1\"/>\n"
        "  <point name=\"p1\" x=\"1\" y=\"1\" z=\"1\"/></shape>"));
    EXPECT_TRUE(contains(msg, "<string>:5:3")) << msg;
    EXPECT_TRUE(contains(msg, "same point")) << msg;
    msg = femto::test::load_error(femto::test::scene_xml(
        "<shape type=\"cylinder\">\n<point name=\"p1\" x=\"nan\" y=\"1\" z=\"1\"/></shape>"));
    EXPECT_TRUE(contains(msg, "<string>:4:1")) << msg;
    EXPECT_TRUE(contains(msg, "finite")) << msg;
    msg = femto::test::load_error(femto::test::scene_xml(
        "<shape type=\"cylinder\">\n<transform name=\"to_world\"><scale x=\"1\" y=\"2\"/>"
        "</transform></shape>"));
    EXPECT_TRUE(contains(msg, "<string>:4:1")) << msg;
    EXPECT_TRUE(contains(msg, "across")) << msg;
    // Shear between the axis and the directions across it.
    Properties sheared("cylinder", {});
    sheared.set_transform(
        "to_world",
        Transform(Transform::Matrix{{{1, 0, 0.3, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}}));
    EXPECT_TRUE(contains(error_of(sheared), "shear"));
}

}  // namespace
