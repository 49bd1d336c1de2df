// Mitsuba's `shapegroup` and `instance` (0.6 and 3): instanced shapes are hit where the same
// shapes written out directly are, with the same hit records, and render the same image;
// Mitsuba 3's restrictions are located errors.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "accel/embree_scene.h"
#include "agreement_util.h"
#include "femto/bsdf.h"
#include "femto/scene.h"
#include "scene_util.h"
#include "shape_test_util.h"

namespace femto {
namespace {

using femto_shape_test::vec_near;

bool contains(const std::string& s, const std::string& part) {
    return s.find(part) != std::string::npos;
}

const char* kBsdfs =
    "<bsdf type=\"diffuse\" id=\"red\"><rgb name=\"reflectance\" value=\"0.8, 0.2, 0.2\"/></bsdf>"
    "<bsdf type=\"diffuse\" id=\"blue\"><rgb name=\"reflectance\" value=\"0.2, 0.3, 0.8\"/></bsdf>"
    "<bsdf type=\"twosided\" id=\"green\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
    "value=\"0.3, 0.7, 0.3\"/></bsdf></bsdf>";

// The group's shapes, each with its own to_world written as `inner` transform operations, and
// `outer` (an instance's) applied after them when the shapes are written out directly.
std::string group_shapes(const std::string& outer) {
    auto tf = [&](const std::string& inner) {
        return "<transform name=\"to_world\">" + inner + outer + "</transform>";
    };
    return "<shape type=\"rectangle\">" + tf("<scale value=\"0.6\"/>") +
           "<ref id=\"red\"/></shape>"
           "<shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0\" z=\"0.5\"/><float "
           "name=\"radius\" value=\"0.3\"/>" +
           tf("<translate x=\"0.1\"/>") +
           "<ref id=\"blue\"/></shape>"
           "<shape type=\"cylinder\"><float name=\"radius\" value=\"0.2\"/>" +
           tf("<translate x=\"-0.4\" y=\"0.3\"/>") +
           "<ref id=\"green\"/></shape>"
           "<shape type=\"cube\">" +
           tf("<scale value=\"0.15\"/><translate x=\"0.4\" y=\"-0.35\" z=\"0.15\"/>") +
           "<ref id=\"red\"/></shape>";
}

// Two placements: a rotation, scale and translation, and a mirror image.
const char* kPlace1 = "<rotate z=\"1\" angle=\"30\"/><scale value=\"0.8\"/><translate x=\"0.6\"/>";
const char* kPlace2 =
    "<scale x=\"-1\"/><rotate x=\"1\" angle=\"20\"/><translate x=\"-0.7\" y=\"0.2\"/>";

std::string frame(const std::string& shapes, const std::string& version = "3.0.0") {
    return "<scene version=\"" + version +
           "\"><integrator type=\"path\"><integer name=\"max_depth\" value=\"3\"/></integrator>"
           "<sensor type=\"perspective\"><float name=\"fov\" value=\"50\"/><transform "
           "name=\"to_world\"><lookat origin=\"0.3, -3, 2.5\" target=\"0, 0, 0.3\" up=\"0, 0, "
           "1\"/></transform><sampler type=\"independent\"><integer name=\"sample_count\" "
           "value=\"8\"/></sampler><film type=\"hdrfilm\"><integer name=\"width\" value=\"24\"/>"
           "<integer name=\"height\" value=\"24\"/><rfilter type=\"box\"/></film></sensor>" +
           std::string(kBsdfs) +
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"4\"/>"
           "<translate z=\"-0.01\"/></transform></shape>"
           "<emitter type=\"point\"><point name=\"position\" x=\"1\" y=\"-1\" z=\"3\"/>"
           "<rgb name=\"intensity\" value=\"8\"/></emitter>" +
           shapes + "</scene>";
}

std::string instanced_scene() {
    return frame("<shape type=\"shapegroup\" id=\"group\">" + group_shapes("") +
                 "</shape>"
                 "<shape type=\"instance\"><ref id=\"group\"/><transform name=\"to_world\">" +
                 kPlace1 +
                 "</transform></shape>"
                 "<shape type=\"instance\"><ref id=\"group\"/><transform name=\"to_world\">" +
                 kPlace2 + "</transform></shape>");
}

std::string direct_scene() { return frame(group_shapes(kPlace1) + group_shapes(kPlace2)); }

// Rays from the camera's position through a grid, and random rays between points of the scene:
// the same hits, with the same records and materials.
TEST(Instancing, HitsMatchTheShapesWrittenDirectly) {
    auto inst = load_scene_string(instanced_scene());
    auto direct = load_scene_string(direct_scene());
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1.5f, 1.5f), h(0.f, 1.2f);
    int hits = 0, on_group = 0;
    for (int i = 0; i < 4000; ++i) {
        const Vec3 o = i % 2 ? Vec3(0.3f, -3, 2.5f) : Vec3(u(rng), u(rng), h(rng) + 0.05f);
        const Vec3 target(u(rng) * 0.8f, u(rng) * 0.8f, h(rng) * 0.5f);
        const Ray ray{o, normalize(target - o), 0.f, kInfinity};
        Hit a, b;
        const bool ha = inst->intersect(ray, a), hb = direct->intersect(ray, b);
        // Rays grazing an edge may go either way under the two scenes' roundings.
        if (ha != hb || (ha && std::abs(a.t - b.t) > 1e-3f)) {
            ADD_FAILURE_AT(__FILE__, __LINE__) << "ray " << i << ": instanced " << ha << " t "
                                               << a.t << ", direct " << hb << " t " << b.t;
            continue;
        }
        EXPECT_EQ(inst->occluded(ray), direct->occluded(ray));
        if (!ha) continue;
        ++hits;
        EXPECT_NEAR(a.t, b.t, 1e-4f * std::max(1.f, b.t)) << i;
        EXPECT_TRUE(vec_near(a.p, b.p, 2e-4)) << i;
        EXPECT_TRUE(vec_near(a.ng, b.ng, 2e-4)) << i;
        EXPECT_TRUE(vec_near(a.sh.n, b.sh.n, 2e-4)) << i;
        // femto's sphere takes its uv from the world axes around its centre (to_world only
        // moves and scales it), so a rotated sphere's uv differ; an instanced sphere's are
        // those of the group's space, as Mitsuba's (object space).
        if (a.shape->type_name() != "sphere") {
            EXPECT_NEAR(a.uv.x, b.uv.x, 2e-4) << i << " " << a.shape->type_name();
            EXPECT_NEAR(a.uv.y, b.uv.y, 2e-4) << i << " " << a.shape->type_name();
        }
        EXPECT_TRUE(vec_near(a.wi, b.wi, 2e-3)) << i;
        EXPECT_EQ(a.shape->bsdf()->id(), b.shape->bsdf()->id()) << i;
        EXPECT_EQ(a.shape->type_name(), b.shape->type_name()) << i;
        on_group += a.shape->type_name() != "rectangle" || a.shape->bsdf()->id() == "red";
        // A ray leaving the hit does not find the same surface again.
        Hit again;
        const Vec3 out = a.ng * (dot(a.ng, ray.d) < 0 ? 1.f : -1.f);
        if (inst->intersect(a.spawn(out), again)) {
            EXPECT_GT(again.t, 1e-4f) << i;
        }
    }
    EXPECT_GT(hits, 2000);
    EXPECT_GT(on_group, 500);
    EXPECT_LT(std::abs(inst->bounds().radius() - direct->bounds().radius()),
              0.01f * direct->bounds().radius());
}

TEST(Instancing, RendersLikeTheShapesWrittenDirectly) {
    constexpr int kRuns = 16;
    auto runs = [&](const std::string& xml, uint64_t seed) {
        std::vector<testing::Cube> out;
        for (int r = 0; r < kRuns; ++r) {
            auto scene = load_scene_string(xml);
            testing::Cube c;
            c.H = c.W = 24, c.T = 1, c.C = 3;
            c.data = testing::render_steady(*scene, seed + uint64_t(r));
            out.push_back(std::move(c));
        }
        return out;
    };
    const auto a = runs(instanced_scene(), 1), b = runs(direct_scene(), 1001);
    test::expect_agree(test::cells_of(a, 1, 1), test::cells_of(b, 1, 1), kRuns,
                       "instanced vs direct");
    // The same seed renders nearly the same image (only rays grazing edges may differ).
    auto si = load_scene_string(instanced_scene());
    auto sd = load_scene_string(direct_scene());
    const std::vector<float> ia = testing::render_steady(*si, 5),
                             ib = testing::render_steady(*sd, 5);
    double diff = 0, total = 0;
    for (size_t i = 0; i < ia.size(); ++i) diff += std::abs(ia[i] - ib[i]), total += ib[i];
    EXPECT_LT(diff, 0.02 * total);
}

// A group's shape may bound a medium: instances of a fog ball render as fog balls written out
// directly, and the scene knows it has media.
TEST(Instancing, MediaInsideAGroup) {
    const std::string fog =
        "<medium type=\"homogeneous\" id=\"fog\"><float name=\"sigma_s\" value=\"1.5\"/>"
        "<float name=\"sigma_a\" value=\"0.3\"/></medium>";
    auto ball = [](const std::string& outer) {
        return "<shape type=\"sphere\"><float name=\"radius\" value=\"0.4\"/><transform "
               "name=\"to_world\"><translate z=\"0.5\"/>" +
               outer +
               "</transform><bsdf type=\"null\"/><ref name=\"interior\" id=\"fog\"/></shape>";
    };
    const std::string instanced = frame(
        fog + "<shape type=\"shapegroup\" id=\"g\">" + ball("") +
        "</shape><shape type=\"instance\"><ref id=\"g\"/><transform name=\"to_world\">" + kPlace1 +
        "</transform></shape><shape type=\"instance\"><ref id=\"g\"/><transform "
        "name=\"to_world\">" +
        kPlace2 + "</transform></shape>");
    const std::string direct = frame(fog + ball(kPlace1) + ball(kPlace2));
    EXPECT_TRUE(load_scene_string(instanced)->has_media());
    constexpr int kRuns = 16;
    auto runs = [&](const std::string& xml, uint64_t seed) {
        std::vector<testing::Cube> out;
        for (int r = 0; r < kRuns; ++r) {
            auto scene = load_scene_string(xml);
            testing::Cube c;
            c.H = c.W = 24, c.T = 1, c.C = 3;
            c.data = testing::render_steady(*scene, seed + uint64_t(r));
            out.push_back(std::move(c));
        }
        return out;
    };
    test::expect_agree(test::cells_of(runs(instanced, 1), 1, 1),
                       test::cells_of(runs(direct, 1001), 1, 1), kRuns, "instanced vs direct fog");
}

// However many instances place a group, its geometry is in the Embree scene once.
TEST(Instancing, GroupGeometryIsStoredOnce) {
    std::string body =
        "<shape type=\"shapegroup\" id=\"g\"><shape type=\"cube\"/>"
        "<shape type=\"cylinder\"/></shape>";
    for (int i = 0; i < 50; ++i)
        body +=
            "<shape type=\"instance\"><ref id=\"g\"/><transform name=\"to_world\">"
            "<translate x=\"" +
            std::to_string(3 * i) + "\"/></transform></shape>";
    auto scene = load_scene_string(test::scene_xml(body));
    EXPECT_EQ(scene->shapes().size(), 50u);
    const detail::EmbreeScene embree(scene->shapes());
    EXPECT_EQ(embree.triangles(), 12u);
    EXPECT_EQ(embree.cylinders(), 1u);
    EXPECT_EQ(embree.instances(), 50u);
    EXPECT_NEAR(embree.bounds().max.x, 148.f, 1e-4f);
    Hit hit;
    ASSERT_TRUE(scene->intersect(Ray{{147, 0, 5}, {0, 0, -1}, 0.f, kInfinity}, hit));
    EXPECT_TRUE(vec_near(hit.p, {147, 0, 1}, 1e-5));
    EXPECT_TRUE(vec_near(hit.ng, {0, 0, 1}, 1e-6));
}

// Rays leaving an instanced sphere (docs/precision.md) at sizes 1e-6 ... 1e6, placed at the
// origin and 1e3 sizes away from it by the instance: outward rays find nothing, inward ones
// the far side at no less than half the exact chord 2 r |cos|.
TEST(Instancing, RaysLeavingAnInstanceNeverHitItAgainAtAnyScale) {
    femto_shape_test::for_each_scale([&](double size, const Vec3& c) {
        auto scene = load_scene_string(test::scene_xml(
            "<shape type=\"shapegroup\" id=\"g\"><shape type=\"sphere\"/></shape>"
            "<shape type=\"instance\"><ref id=\"g\"/><transform name=\"to_world\"><scale "
            "value=\"" +
            test::xml_number(size) + "\"/><rotate x=\"1\" y=\"2\" angle=\"40\"/><translate x=\"" +
            test::xml_number(c.x) + "\" y=\"" + test::xml_number(c.y) + "\" z=\"" +
            test::xml_number(c.z) + "\"/></transform></shape>"));
        // Every hit is on the sphere; inward rays find its far side, no closer than the chord.
        int missed_inside = 0;
        const int hits = femto_shape_test::expect_rays_leave(
            *scene, c, size, [&](const Hit& hit, const Hit* again, const Vec3& in) {
                EXPECT_NEAR(distance_between(hit.p, c), size, 1e-5 * (size + max_abs_component(c)));
                if (!again) return ++missed_inside, false;
                return distance_between(hit.p, again->p) < size * std::abs(dot(in, hit.ng));
            });
        EXPECT_GT(hits, 200);
        EXPECT_EQ(missed_inside, 0);
    });
}

// Mitsuba 0.6 writes the same (toWorld is upgraded with the other camelCase names).
TEST(Instancing, Mitsuba06Scene) {
    std::string xml = instanced_scene();
    for (size_t at; (at = xml.find("to_world")) != std::string::npos;)
        xml.replace(at, 8, "toWorld");
    xml.replace(xml.find("3.0.0"), 5, "0.6.0");
    xml.replace(xml.find("max_depth"), 9, "maxDepth");
    xml.replace(xml.find("sample_count"), 12, "sampleCount");
    auto old = load_scene_string(xml);
    auto now = load_scene_string(instanced_scene());
    Hit a, b;
    const Ray ray{
        {0.3f, -3, 2.5f}, normalize(Vec3(0.6f, 0.1f, 0.3f) - Vec3(0.3f, -3, 2.5f)), 0.f, kInfinity};
    ASSERT_TRUE(now->intersect(ray, b));
    ASSERT_TRUE(old->intersect(ray, a));
    EXPECT_TRUE(vec_near(a.p, b.p, 0));
}

TEST(Instancing, ErrorsAreLocated) {
    auto scene = [](const std::string& body) { return test::scene_xml(body); };
    // An unknown id, at the <ref>.
    std::string msg = test::load_error(
        scene("<shape type=\"shapegroup\" id=\"group\"><shape type=\"sphere\"/></shape>\n"
              "<shape type=\"instance\">\n  <ref id=\"grop\"/></shape>"));
    EXPECT_TRUE(contains(msg, "<string>:5:3")) << msg;
    EXPECT_TRUE(contains(msg, "grop")) << msg;
    EXPECT_TRUE(contains(msg, "group")) << msg;  // the suggestion
    // A reference to something else than a shapegroup.
    msg = test::load_error(
        scene("<bsdf type=\"diffuse\" id=\"red\"/>\n<shape type=\"instance\">\n  <ref "
              "id=\"red\"/></shape>"));
    EXPECT_TRUE(contains(msg, "<string>:5:3")) << msg;
    EXPECT_TRUE(contains(msg, "shapegroup")) << msg;
    msg = test::load_error(
        scene("<shape type=\"sphere\" id=\"ball\"/>\n<shape type=\"instance\">\n  <ref "
              "id=\"ball\"/></shape>"));
    EXPECT_TRUE(contains(msg, "<string>:5:3")) << msg;
    EXPECT_TRUE(contains(msg, "type=\"sphere\"")) << msg;
    msg = test::load_error(scene("<shape type=\"instance\">\n</shape>"));
    EXPECT_TRUE(contains(msg, "<string>:3:1")) << msg;
    EXPECT_TRUE(contains(msg, "exactly one")) << msg;
    // An emitter in a shapegroup, at its shape.
    msg = test::load_error(
        scene("<shape type=\"shapegroup\" id=\"g\">\n  <shape type=\"sphere\"><emitter "
              "type=\"area\"/></shape></shape>"));
    EXPECT_TRUE(contains(msg, "<string>:4:3")) << msg;
    EXPECT_TRUE(contains(msg, "emitters")) << msg;
    // Nested instancing.
    msg = test::load_error(
        scene("<shape type=\"shapegroup\" id=\"a\"><shape type=\"sphere\"/></shape>\n"
              "<shape type=\"shapegroup\" id=\"b\">\n  <shape type=\"instance\"><ref "
              "id=\"a\"/></shape></shape>"));
    EXPECT_TRUE(contains(msg, "<string>:5:3")) << msg;
    EXPECT_TRUE(contains(msg, "nested instancing")) << msg;
    msg = test::load_error(
        scene("<shape type=\"shapegroup\" id=\"a\">\n  <bsdf type=\"diffuse\"/></shape>"));
    EXPECT_TRUE(contains(msg, "<string>:4:3")) << msg;
    EXPECT_TRUE(contains(msg, "only shapes")) << msg;
    msg = test::load_error(scene(
        "<shape type=\"shapegroup\" id=\"a\"><shape type=\"sphere\"/></shape>\n<shape "
        "type=\"instance\"><ref id=\"a\"/>\n  <transform name=\"to_world\"><matrix value=\"1 0 0 0 "
        "0 1 0 0 0 0 1 0 0 0 0.5 1\"/></transform></shape>"));
    EXPECT_TRUE(contains(msg, "<string>:5:3")) << msg;
    EXPECT_TRUE(contains(msg, "affine")) << msg;
    // A shapegroup takes no to_world (an instance places it).
    msg = test::load_error(
        scene("<shape type=\"shapegroup\" id=\"a\"><shape type=\"sphere\"/>\n  <transform "
              "name=\"to_world\"><translate x=\"1\"/></transform></shape>"));
    EXPECT_TRUE(contains(msg, "<string>:4:3")) << msg;
}

}  // namespace
}  // namespace femto
