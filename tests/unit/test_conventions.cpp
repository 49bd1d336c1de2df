// Mitsuba's geometric conventions, locked: lookat frame, transform order, rotation handedness,
// camera orientation, rectangle and cube extents through the XML loader.
#include <gtest/gtest.h>

#include "femto/sensor.h"
#include "scene_util.h"

using namespace femto;
using femto::test::scene_xml;

namespace {
void expect_near(const Vec3& a, const Vec3& b, float tol = 1e-5f) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}
}  // namespace

TEST(Conventions, LookatFrame) {
    // Mitsuba: columns are left = cross(up, dir), new_up = cross(dir, left), dir, origin.
    const Transform t = Transform::look_at({1, 2, 3}, {1, 2, 2}, {0, 1, 0});
    expect_near(t.vector({0, 0, 1}), {0, 0, -1});  // local +z looks at the target
    expect_near(t.vector({1, 0, 0}), {-1, 0, 0});  // local +x is the viewer's left
    expect_near(t.vector({0, 1, 0}), {0, 1, 0});   // local +y is up
    expect_near(t.point({0, 0, 0}), {1, 2, 3});
    // An up vector not perpendicular to the view direction is orthogonalised.
    const Transform t2 = Transform::look_at({0, 0, 0}, {0, 0, 5}, {0, 1, 1});
    expect_near(t2.vector({0, 1, 0}), {0, 1, 0});
}

// Only the directions matter: an up of 1e30 or 1e-30, or a target 1e-30 away, is as good as a
// unit one (in float their squared lengths overflowed or vanished: "parallel", "equals").
TEST(Conventions, LookatTakesAnyScaleOfUpAndDistance) {
    for (const float s : {1e-30f, 1e30f, 3e38f}) {
        const Transform t = Transform::look_at({1, 2, 3}, {1, 2, 2}, {0, s, 0});
        expect_near(t.vector({0, 0, 1}), {0, 0, -1});
        expect_near(t.vector({0, 1, 0}), {0, 1, 0});
    }
    const Transform near = Transform::look_at({0, 0, 0}, {0, 0, 1e-30f}, {0, 1, 0});
    expect_near(near.vector({0, 0, 1}), {0, 0, 1});
    const Transform far = Transform::look_at({0, 0, 0}, {0, 0, -1e30f}, {0, 1, 0});
    expect_near(far.vector({0, 0, 1}), {0, 0, -1});
    EXPECT_THROW(Transform::look_at({0, 0, 0}, {0, 0, 1}, {0, 0, 0}), std::domain_error);
    EXPECT_THROW(Transform::look_at({0, 0, 0}, {0, 0, 1}, {0, 0, 1e30f}), std::domain_error);
    EXPECT_THROW(Transform::look_at({1, 1, 1}, {1, 1, 1}, {0, 1, 0}), std::domain_error);
}

TEST(Conventions, RotationIsRightHandedInDegrees) {
    expect_near(Transform::rotate({0, 0, 1}, 90).vector({1, 0, 0}), {0, 1, 0});
    expect_near(Transform::rotate({1, 0, 0}, 90).vector({0, 0, 1}), {0, -1, 0});
    expect_near(Transform::rotate({0, 1, 0}, 90).vector({0, 0, 1}), {1, 0, 0});
}

TEST(Conventions, TransformsApplyInDocumentOrder) {
    // scale, then translate: (1,0,0) -> (2,0,0) -> (3,0,0); the other order gives (4,0,0).
    auto first_vertex_x = [](const std::string& ops) {
        auto scene =
            load_scene_string(scene_xml("<shape type=\"rectangle\"><transform name=\"to_world\">" +
                                        ops + "</transform></shape>"));
        float max_x = -1e30f;
        for (const Vec3& p : scene->shapes()[0]->mesh().positions) max_x = std::max(max_x, p.x);
        return max_x;
    };
    EXPECT_NEAR(first_vertex_x("<scale value=\"2\"/><translate x=\"1\"/>"), 3.f, 1e-6f);
    EXPECT_NEAR(first_vertex_x("<translate x=\"1\"/><scale value=\"2\"/>"), 4.f, 1e-6f);
    // <matrix> lists rows.
    EXPECT_NEAR(first_vertex_x("<matrix value=\"1 0 0 5  0 1 0 0  0 0 1 0  0 0 0 1\"/>"), 6.f,
                1e-6f);
}

TEST(Conventions, RectangleAndCube) {
    // The cube sits far from the rectangle so that the ray below only meets the rectangle.
    auto scene = load_scene_string(
        scene_xml("<shape type=\"rectangle\"/><shape type=\"cube\"><transform name=\"to_world\">"
                  "<translate x=\"10\"/></transform></shape>"));
    const Shape& rect = *scene->shapes()[0];
    EXPECT_NEAR(rect.surface_area(), 4.f, 1e-6f);
    for (const Vec3& p : rect.mesh().positions) {
        EXPECT_EQ(std::abs(p.x), 1.f);
        EXPECT_EQ(std::abs(p.y), 1.f);
        EXPECT_EQ(p.z, 0.f);
    }
    // The rectangle faces +z: a ray from above hits its front side.
    Hit hit;
    ASSERT_TRUE(scene->intersect(Ray{{0.2f, 0.3f, 5}, {0, 0, -1}, 0, kInfinity}, hit));
    expect_near(hit.ng, {0, 0, 1});
    expect_near(hit.p, {0.2f, 0.3f, 0});
    const Shape& cube = *scene->shapes()[1];
    EXPECT_NEAR(cube.surface_area(), 24.f, 1e-5f);
    Bounds3 b;
    for (const Vec3& p : cube.mesh().positions) b.expand(p);
    expect_near(b.min, {9, -1, -1});
    expect_near(b.max, {11, 1, 1});
}

TEST(Conventions, PerspectiveCameraOrientation) {
    // Identity to_world: the camera looks along +z; the image's left edge sees +x, the top +y.
    auto scene = load_scene_string(scene_xml(
        "<sensor type=\"perspective\"><float name=\"fov\" value=\"90\"/><film type=\"hdrfilm\">"
        "<integer name=\"width\" value=\"20\"/><integer name=\"height\" "
        "value=\"10\"/></film></sensor>"
        "<shape type=\"rectangle\"/>"));
    const Sensor& s = scene->sensor();
    expect_near(s.sample_ray({10, 5}, {}).d, {0, 0, 1});
    const Vec3 left = s.sample_ray({0, 5}, {}).d;
    EXPECT_NEAR(left.x / left.z, 1.f, 1e-5f);  // fov 90 along x: tan(45) at the edge
    const Vec3 top = s.sample_ray({10, 0}, {}).d;
    EXPECT_NEAR(top.y / top.z, 0.5f, 1e-5f);  // aspect 2
}
