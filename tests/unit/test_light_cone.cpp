// The light's cone at a shading point (thesis ch. 3: the solid angle "subtended by a pixel and
// the light source", what a prefiltering material filters the light directions over):
// Shape::subtended_half_angle() and Emitter::subtended_half_angle() against their geometry,
// footprint_light_cone()'s turn of a near light's direction across a pixel, and
// sample_emitter(scene, Hit&, sampler) setting PixelFootprint::light_cone for camera hits only.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "femto/host.h"
#include "femto/scene.h"
#include "femto/transport.h"
#include "scene_util.h"

namespace {

using namespace femto;
using femto::test::scene_xml;

/// The scene's emitter of the given type (the first one).
const Emitter& emitter_of(const Scene& scene, const std::string& type) {
    for (const Emitter* e : scene.emitters())
        if (e->type_name() == type) return *e;
    throw std::runtime_error("no emitter of type " + type);
}

constexpr const char* kLights =
    "<shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0\" z=\"3\"/>"
    "<float name=\"radius\" value=\"1\"/><emitter type=\"area\"/></shape>"
    "<shape type=\"rectangle\"><transform name=\"to_world\"><translate z=\"-5\"/></transform>"
    "<emitter type=\"area\"/></shape>"
    "<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"4\" z=\"0\"/></emitter>"
    "<emitter type=\"directional\"><vector name=\"direction\" x=\"0\" y=\"0\" z=\"-1\"/>"
    "</emitter>";

TEST(LightCone, ShapesSubtendTheirBoundingCone) {
    const auto scene = load_scene_string(scene_xml(kLights));
    const Shape *sphere = nullptr, *rectangle = nullptr;
    for (const auto& s : scene->shapes()) (s->is_sphere() ? sphere : rectangle) = s.get();
    ASSERT_TRUE(sphere && rectangle);
    // A sphere: exactly the cone tangent to it; pi from inside.
    EXPECT_NEAR(sphere->subtended_half_angle(Vec3(0, 0, 0)), std::asin(1.0 / 3.0), 1e-6);
    EXPECT_NEAR(sphere->subtended_half_angle(Vec3(0, 0, -7)), std::asin(0.1), 1e-6);
    EXPECT_FLOAT_EQ(sphere->subtended_half_angle(Vec3(0, 0.5f, 3)), kPi);
    // The 2 x 2 rectangle at z = -5: the cone around its bounding sphere (radius sqrt 2).
    EXPECT_NEAR(rectangle->subtended_half_angle(Vec3(0, 0, 0)), std::asin(std::sqrt(2.0) / 5),
                1e-6);
    EXPECT_FLOAT_EQ(rectangle->subtended_half_angle(Vec3(0.5f, 0, -5)), kPi);
}

TEST(LightCone, EmittersReportTheirExtent) {
    const auto scene =
        load_scene_string(scene_xml(std::string(kLights) + "<emitter type=\"constant\"/>"));
    for (const Emitter* e : scene->emitters()) {
        const float cone = e->subtended_half_angle(Vec3(0, 0, 0));
        if (e->type_name() == "area") {
            EXPECT_FLOAT_EQ(cone, e->shape()->subtended_half_angle(Vec3(0, 0, 0)));
            EXPECT_GT(cone, 0.f);
        } else if (e->type_name() == "constant") {
            EXPECT_FLOAT_EQ(cone, kPi);  // light from every direction
        } else {
            EXPECT_EQ(cone, 0.f) << e->type_name();  // point-like and collimated
        }
    }
}

TEST(LightCone, FootprintConeAddsTheTurnOfANearLightAcrossThePixel) {
    const auto scene = load_scene_string(scene_xml(kLights));
    PixelFootprint f;
    f.valid = true;
    f.dp_dx = Vec3(0.02f, 0, 0.5f);  // the part along the light's direction does not turn it
    f.dp_dy = Vec3(0, 0.01f, 0);
    EmitterSample point;
    point.emitter = &emitter_of(*scene, "point");
    point.wi = Vec3(0, 0, 1);
    point.distance = 4;
    // Half the pixel's turn of the direction toward the point light: 0.5 * 0.02 / 4.
    EXPECT_NEAR(footprint_light_cone(f, Vec3(0, 0, 0), point), 0.0025, 1e-7);
    // A distant light's direction does not turn with the position.
    EmitterSample directional = point;
    directional.emitter = &emitter_of(*scene, "directional");
    EXPECT_EQ(footprint_light_cone(f, Vec3(0, 0, 0), directional), 0.f);
    // An area light: its cone plus the turn toward the sampled point.
    EmitterSample area = point;
    area.emitter = scene->shapes()[0]->emitter();
    area.distance = 2;
    EXPECT_NEAR(footprint_light_cone(f, Vec3(0, 0, 0), area),
                area.emitter->subtended_half_angle(Vec3(0, 0, 0)) + 0.005f, 1e-6);
}

TEST(LightCone, SampleEmitterSetsItForCameraHitsOnly) {
    const auto scene = load_scene_string(
        scene_xml("<shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0\" z=\"3\"/>"
                  "<float name=\"radius\" value=\"1\"/><emitter type=\"area\"/></shape>"));
    auto object = create_default_object(PluginKind::Sampler, "independent", {});
    Sampler& sampler = static_cast<Sampler&>(*object);
    sampler.start(7, 0, 0);
    Hit camera_hit, later_hit;
    camera_hit.footprint.valid = true;
    const EmitterSample a = sample_emitter(*scene, camera_hit, sampler);
    ASSERT_GT(a.pdf, 0.f);
    // No footprint derivatives: the sphere's own cone, asin(1/3).
    EXPECT_NEAR(camera_hit.footprint.light_cone, std::asin(1.0 / 3.0), 1e-6);
    sample_emitter(*scene, later_hit, sampler);
    EXPECT_EQ(later_hit.footprint.light_cone, 0.f);
}

}  // namespace
