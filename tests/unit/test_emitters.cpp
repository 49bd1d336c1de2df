// Tests of the emitter plugins: point (I / d^2), spot (Mitsuba's falloff), collimated (a beam
// of finite radius) and area (front-side emission, sample/pdf consistency with the host's
// shape sampling, and irradiance from a disk and a sphere against closed forms).
//
// Tolerances: deterministic quantities are computed in float from float inputs of magnitude
// <= 10, so they agree to a few ulps (1e-6 relative) unless stated otherwise. Monte Carlo
// estimates use N independent samples and must lie within 5 standard errors (estimated from
// the same samples) of the closed form, plus the stated bias of the geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "femto/emitter.h"
#include "femto/error.h"
#include "femto/host.h"
#include "femto/plugin.h"
#include "femto/shape.h"
#include "femto/transform.h"
#include "shape_test_util.h"

namespace {

using femto::Color;
using femto::Emitter;
using femto::EmitterSample;
using femto::Hit;
using femto::PluginKind;
using femto::Properties;
using femto::Shape;
using femto::Transform;
using femto::Vec2;
using femto::Vec3;
using femto_shape_test::brute_intersect;
using femto_shape_test::make_emitter;
using femto_shape_test::make_shape;
using femto_shape_test::ray_toward;
using femto_shape_test::vec_near;

constexpr double kPiD = 3.14159265358979323846;

::testing::AssertionResult color_near(const Color& a, const Color& b, double rel) {
    for (int k = 0; k < 3; ++k)
        if (!(std::abs(double(a[k]) - double(b[k])) <= rel * std::abs(double(b[k])) + 1e-30))
            return ::testing::AssertionFailure()
                   << "(" << a.r << ", " << a.g << ", " << a.b << ") != (" << b.r << ", " << b.g
                   << ", " << b.b << ") +- " << rel << " relative";
    return ::testing::AssertionSuccess();
}

std::string error_of(const Properties& props) {
    try {
        make_emitter(props);
    } catch (const femto::SceneError& e) {
        return e.what();
    }
    return "(no error)";
}

TEST(EmitterSchema, ParametersAreDocumented) {
    const std::map<std::string, std::vector<std::string>> expected = {
        {"area", {"radiance"}},
        {"point", {"intensity", "position", "to_world"}},
        {"spot", {"intensity", "cutoff_angle", "beam_width", "to_world"}},
        {"collimated", {"radius", "irradiance", "power", "to_world"}},
    };
    // Every emitter also takes the pulse parameters (design section 4) and the medium it sits
    // in: the Emitter base class reads them, and they come first.
    const std::vector<std::string> pulse = {"pulse", "pulse_width", "pulse_sigma", "time_offset",
                                            "medium"};
    for (auto [type, names] : expected) {
        names.insert(names.begin(), pulse.begin(), pulse.end());
        const femto::PluginDescriptor& d = femto::find_plugin(PluginKind::Emitter, type);
        EXPECT_EQ(d.kind, PluginKind::Emitter);
        ASSERT_EQ(d.params.size(), names.size()) << type;
        for (size_t i = 0; i < names.size(); ++i) {
            EXPECT_EQ(d.params[i].name, names[i]) << type;
            EXPECT_TRUE(d.params[i].doc && *d.params[i].doc) << type;
        }
    }
}

// -- point ------------------------------------------------------------------------------------

TEST(EmitterPoint, WeightIsIntensityOverDistanceSquared) {
    Properties by_position("point", {});
    by_position.set_color("intensity", {1, 2, 3});
    by_position.set_point("position", {1, 2, 3});
    Properties by_transform("point", {});
    by_transform.set_color("intensity", {1, 2, 3});
    by_transform.set_transform("to_world", Transform::translate({1, 2, 3}));
    for (const Properties& props : {by_position, by_transform}) {
        auto e = make_emitter(props);
        ASSERT_TRUE(e);
        EXPECT_TRUE(e->is_delta());
        const EmitterSample s = e->sample_direct({1, 2, -1}, {0.3f, 0.7f});
        EXPECT_EQ(s.pdf, 1.f);
        EXPECT_TRUE(s.delta);
        EXPECT_EQ(s.distance, 4.f);
        EXPECT_TRUE(vec_near(s.wi, {0, 0, 1}, 0));
        EXPECT_TRUE(vec_near(s.p, {1, 2, 3}, 0));
        EXPECT_TRUE(color_near(s.weight, Color(1, 2, 3) / 16.f, 1e-6));
        // Off axis: d^2 = 3^2 + 4^2.
        const EmitterSample s2 = e->sample_direct({4, 6, 3}, {0.f, 0.f});
        EXPECT_NEAR(s2.distance, 5.f, 1e-6);
        EXPECT_TRUE(color_near(s2.weight, Color(1, 2, 3) / 25.f, 1e-6));
        EXPECT_TRUE(vec_near(s2.wi, {-0.6f, -0.8f, 0}, 1e-6));
        // At the light itself there is no direction: no contribution.
        EXPECT_EQ(e->sample_direct({1, 2, 3}, {0.5f, 0.5f}).pdf, 0.f);
    }
    auto def = make_emitter(Properties("point", {}));
    ASSERT_TRUE(def);
    EXPECT_TRUE(color_near(def->sample_direct({0, 0, 2}, {}).weight, Color(0.25f), 1e-6));
}

TEST(EmitterPoint, PositionAndToWorldExcludeEachOther) {
    Properties props("point", {});
    props.set_point("position", {1, 2, 3});
    props.set_transform("to_world", Transform::translate({1, 2, 3}));
    EXPECT_NE(error_of(props).find("position"), std::string::npos);
    Properties negative("point", {});
    negative.set_color("intensity", {1, -1, 1});
    EXPECT_THROW(make_emitter(negative), femto::SceneError);
}

// -- spot -------------------------------------------------------------------------------------

/// A spot at (0,0,5) shining down -z; the weight at distance 4 and angle `deg` off its axis.
Color spot_weight(const Emitter& e, double deg) {
    const double a = deg * kPiD / 180.0;
    const Vec3 ref(float(4 * std::sin(a)), 0.f, float(5 - 4 * std::cos(a)));
    const EmitterSample s = e.sample_direct(ref, {0.5f, 0.5f});
    if (s.pdf == 0) return Color(0.f);
    EXPECT_EQ(s.pdf, 1.f);
    EXPECT_TRUE(s.delta);
    EXPECT_NEAR(s.distance, 4.f, 1e-5);
    return s.weight * 16.f;  // * d^2: the falloff times the intensity
}

TEST(EmitterSpot, MitsubaFalloff) {
    Properties props("spot", {});
    props.set_color("intensity", Color(10.f));
    props.set_transform("to_world", Transform::look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0}));
    auto e = make_emitter(props);
    ASSERT_TRUE(e);
    EXPECT_TRUE(e->is_delta());
    // Defaults: cutoff 20 degrees, beam width 15. Full intensity inside the beam, linear in
    // angle between 15 and 20, nothing beyond. The angle goes through float acos near
    // cos = 0.95 (error ~2e-7 rad over a 0.087 rad ramp), hence 1e-5.
    for (const auto& [deg, f] : std::vector<std::pair<double, double>>{
             {0, 1}, {10, 1}, {14.9, 1}, {16, 0.8}, {17.5, 0.5}, {19, 0.2}, {19.9, 0.02}}) {
        EXPECT_NEAR(spot_weight(*e, deg).r, 10 * f, 1e-4) << deg << " degrees";
    }
    for (const double deg : {20.1, 30.0, 90.0, 135.0, 180.0})
        EXPECT_EQ(spot_weight(*e, deg).r, 0.f) << deg << " degrees";
    // On the axis, the weight is I / d^2 exactly as for a point light.
    const EmitterSample s = e->sample_direct({0, 0, 1}, {});
    EXPECT_TRUE(vec_near(s.wi, {0, 0, 1}, 1e-6));
    EXPECT_TRUE(color_near(s.weight, Color(10.f / 16.f), 1e-6));
}

TEST(EmitterSpot, CustomAnglesAndBadValues) {
    Properties props("spot", {});
    props.set_float("cutoff_angle", 30);
    props.set_float("beam_width", 10);
    props.set_transform("to_world", Transform::look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0}));
    auto e = make_emitter(props);
    ASSERT_TRUE(e);
    EXPECT_NEAR(spot_weight(*e, 20).r, 0.5, 1e-5);
    EXPECT_NEAR(spot_weight(*e, 9).r, 1.0, 1e-6);
    EXPECT_EQ(spot_weight(*e, 31).r, 0.f);

    // beam_width > cutoff_angle: clamped to the cutoff (as Mitsuba), a hard-edged cone.
    Properties wide("spot", {});
    wide.set_float("beam_width", 25);
    wide.set_transform("to_world", Transform::look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0}));
    auto w = make_emitter(wide);
    ASSERT_TRUE(w);
    EXPECT_NEAR(spot_weight(*w, 19.5).r, 1.0, 1e-6);
    EXPECT_EQ(spot_weight(*w, 20.5).r, 0.f);

    for (const double cutoff : {0.0, -5.0, 181.0}) {
        Properties bad("spot", {});
        bad.set_float("cutoff_angle", cutoff);
        EXPECT_NE(error_of(bad).find("cutoff_angle"), std::string::npos) << cutoff;
    }
    Properties bad_beam("spot", {});
    bad_beam.set_float("beam_width", -1);
    EXPECT_NE(error_of(bad_beam).find("beam_width"), std::string::npos);
}

// -- collimated -------------------------------------------------------------------------------

TEST(EmitterCollimated, InsideAndOutsideTheBeam) {
    Properties props("collimated", {});
    props.set_float("radius", 0.5);
    props.set_color("irradiance", {1, 2, 3});
    auto e = make_emitter(props);
    ASSERT_TRUE(e);
    EXPECT_TRUE(e->is_delta());
    // Default frame: from the origin along +z.
    const EmitterSample in = e->sample_direct({0.3f, 0.2f, 4}, {0.1f, 0.9f});
    EXPECT_EQ(in.pdf, 1.f);
    EXPECT_TRUE(in.delta);
    EXPECT_TRUE(vec_near(in.wi, {0, 0, -1}, 0));
    EXPECT_EQ(in.distance, 4.f);
    EXPECT_TRUE(vec_near(in.p, {0.3f, 0.2f, 0}, 1e-6));
    EXPECT_TRUE(color_near(in.weight, {1, 2, 3}, 0));
    // The irradiance does not fall off with distance.
    EXPECT_TRUE(color_near(e->sample_direct({0, -0.49f, 1000}, {}).weight, {1, 2, 3}, 0));

    for (const Vec3& out :
         {Vec3(0.5f, 0.4f, 4), Vec3(0.6f, 0, 0.1f), Vec3(0, 0, -1), Vec3(0.1f, 0.1f, -0.001f)}) {
        const EmitterSample s = e->sample_direct(out, {0.5f, 0.5f});
        EXPECT_EQ(s.pdf, 0.f) << out.x << " " << out.y << " " << out.z;
        EXPECT_TRUE(s.weight.is_black());
    }
}

TEST(EmitterCollimated, ToWorldAndPower) {
    // rotate 90 degrees about +y maps +z to +x: a beam from (1,2,3) along +x.
    Properties props("collimated", {});
    props.set_float("radius", 0.25);
    props.set_color("power", Color(float(2 * kPiD * 0.25 * 0.25)));
    props.set_transform("to_world",
                        Transform::translate({1, 2, 3}) * Transform::rotate({0, 1, 0}, 90));
    auto e = make_emitter(props);
    ASSERT_TRUE(e);
    const EmitterSample s = e->sample_direct({4, 2.1f, 3.1f}, {});
    EXPECT_EQ(s.pdf, 1.f);
    EXPECT_TRUE(vec_near(s.wi, {-1, 0, 0}, 1e-6));
    EXPECT_NEAR(s.distance, 3.f, 1e-6);
    EXPECT_TRUE(color_near(s.weight, Color(2.f), 1e-6));  // power / (pi r^2)
    EXPECT_EQ(e->sample_direct({4, 2.3f, 3}, {}).pdf, 0.f);
    EXPECT_EQ(e->sample_direct({0.9f, 2, 3}, {}).pdf, 0.f);
}

// Without a radius the beam is Mitsuba 0.6's: one ray carrying `power`, a delta in position
// and direction; nothing samples it directly.
TEST(EmitterCollimated, WithoutRadiusIsAThinBeam) {
    Properties props("collimated", {});
    props.set_color("power", Color(1, 2, 3));
    props.set_transform("to_world", Transform::translate({1, 2, 3}) *
                                        Transform::rotate({0, 1, 0}, 90));  // +z -> +x
    auto e = make_emitter(props);
    ASSERT_TRUE(e);
    EXPECT_TRUE(e->is_delta());
    EXPECT_EQ(e->sample_direct({4, 2, 3}, {0.5f, 0.5f}).pdf, 0.f);  // even on the beam
    for (const Vec2 u : {Vec2(0.1f, 0.9f), Vec2(0.7f, 0.3f)}) {
        const femto::EmissionSample es = e->sample_emission(u, {0.4f, 0.6f});
        EXPECT_TRUE(es.valid());
        EXPECT_TRUE(es.delta_position && es.delta_direction);
        EXPECT_TRUE(vec_near(es.p, {1, 2, 3}, 1e-6));
        EXPECT_TRUE(vec_near(es.d, {1, 0, 0}, 1e-6));
        EXPECT_TRUE(color_near(es.weight, {1, 2, 3}, 0));
        float pos = 0, dir = 0;
        e->pdf_emission(es, es.d, pos, dir);
        EXPECT_EQ(pos, 1.f);
        EXPECT_EQ(dir, 1.f);
    }
    const femto::EmissionSample def =
        make_emitter(Properties("collimated", {}))->sample_emission({}, {});
    EXPECT_TRUE(color_near(def.weight, Color(1.f), 0));  // Mitsuba's default power
}

TEST(EmitterCollimated, BadRadiusAndIrradiance) {
    for (const double r : {0.0, -1.0, std::nan("")}) {
        Properties props("collimated", {});
        props.set_float("radius", r);
        EXPECT_NE(error_of(props).find("radius"), std::string::npos);
    }
    Properties thin("collimated", {});  // the irradiance of a thin beam is infinite
    thin.set_color("irradiance", Color(1.f));
    const std::string msg = error_of(thin);
    EXPECT_NE(msg.find("infinitely thin"), std::string::npos) << msg;
    Properties both("collimated", {});
    both.set_float("radius", 1);
    both.set_color("irradiance", Color(1.f));
    both.set_color("power", Color(1.f));
    EXPECT_THROW(make_emitter(both), femto::SceneError);
}

// -- area -------------------------------------------------------------------------------------

struct Lit {
    std::shared_ptr<Shape> shape;
    std::shared_ptr<Emitter> emitter;
};

Lit area_light(Properties shape_props, const Color& radiance) {
    Properties ep("area", {});
    ep.set_color("radiance", radiance);
    Lit lit;
    lit.emitter = make_emitter(ep);
    lit.shape = make_shape(shape_props);
    if (lit.emitter && lit.shape) lit.emitter->set_shape(lit.shape.get());
    return lit;
}

/// A unit rectangle at z = 2 facing down (-z), scaled to 1.5 x 1.
Properties facing_down_rectangle() {
    Properties props("rectangle", {});
    props.set_transform("to_world", Transform::translate({0, 0, 2}) *
                                        Transform::rotate({1, 0, 0}, 180) *
                                        Transform::scale({1.5f, 1, 1}));
    return props;
}

TEST(EmitterArea, SampleAndPdfAreConsistent) {
    const Color radiance(1, 2, 3);
    for (const Properties& sp : {facing_down_rectangle(), [] {
                                     Properties s("sphere", {});
                                     s.set_point("center", {0.5f, 0.2f, 3});
                                     s.set_float("radius", 0.7);
                                     return s;
                                 }()}) {
        const Lit lit = area_light(sp, radiance);
        ASSERT_TRUE(lit.emitter && lit.shape);
        EXPECT_FALSE(lit.emitter->is_delta());
        const Vec3 ref(0.3f, -0.2f, 0.f);
        std::mt19937 rng(7);
        std::uniform_real_distribution<float> uni(0.f, 1.f);
        for (int i = 0; i < 200; ++i) {
            const EmitterSample s = lit.emitter->sample_direct(ref, {uni(rng), uni(rng)});
            ASSERT_GT(s.pdf, 0.f) << sp.plugin_type();
            EXPECT_FALSE(s.delta);
            // weight = radiance / pdf: two float roundings.
            EXPECT_TRUE(color_near(s.weight * s.pdf, radiance, 1e-6));
            EXPECT_NEAR(femto::length(s.wi), 1.f, 1e-6);
            EXPECT_TRUE(vec_near(ref + s.wi * s.distance, s.p, 1e-5));
            EXPECT_LT(femto::dot(s.wi, s.n), 0.f);
            // The same point, found by a ray as an integrator would: the host's hit record
            // gives the same pdf. The hit point agrees with s.p to ~1e-6 relative and the
            // cosine at the light is >= 0.3 here, so the pdfs agree to ~1e-5; 1e-4 is used.
            Hit hit;
            ASSERT_TRUE(brute_intersect(*lit.shape, ray_toward(ref, s.p), hit));
            EXPECT_TRUE(vec_near(hit.p, s.p, 1e-4));
            EXPECT_NEAR(lit.emitter->pdf_direct(ref, hit), s.pdf, 1e-4 * s.pdf);
            EXPECT_TRUE(color_near(lit.emitter->eval(hit, -s.wi), radiance, 0));
        }
    }
}

TEST(EmitterArea, OnlyTheFrontSideEmits) {
    const Color radiance(4.f);
    Properties up("rectangle", {});  // at z = 2, normal +z: its back faces the origin
    up.set_transform("to_world", Transform::translate({0, 0, 2}));
    const Lit back = area_light(up, radiance);
    ASSERT_TRUE(back.emitter && back.shape);
    const Vec3 below(0.1f, 0.2f, 0.f), above(0.1f, 0.2f, 4.f);
    for (const Vec2 u : {Vec2(0.1f, 0.2f), Vec2(0.5f, 0.5f), Vec2(0.9f, 0.7f)}) {
        const EmitterSample s = back.emitter->sample_direct(below, u);
        EXPECT_EQ(s.pdf, 0.f);
        EXPECT_TRUE(s.weight.is_black());
        EXPECT_GT(back.emitter->sample_direct(above, u).pdf, 0.f);
    }
    Hit hit;
    ASSERT_TRUE(brute_intersect(*back.shape, ray_toward(below, {0, 0, 2}), hit));
    EXPECT_EQ(back.emitter->pdf_direct(below, hit), 0.f);
    EXPECT_TRUE(back.emitter->eval(hit, {0, 0, -1}).is_black());
    EXPECT_TRUE(color_near(back.emitter->eval(hit, {0, 0, 1}), radiance, 0));

    // flip_normals turns the emitting side toward the origin (the host flips hit.ng and the
    // sampled normal).
    up.set_bool("flip_normals", true);
    const Lit front = area_light(up, radiance);
    ASSERT_TRUE(front.emitter && front.shape);
    const EmitterSample s = front.emitter->sample_direct(below, {0.3f, 0.4f});
    EXPECT_GT(s.pdf, 0.f);
    EXPECT_TRUE(color_near(s.weight * s.pdf, radiance, 1e-6));
    ASSERT_TRUE(brute_intersect(*front.shape, ray_toward(below, {0, 0, 2}), hit));
    EXPECT_GT(front.emitter->pdf_direct(below, hit), 0.f);
    EXPECT_TRUE(color_near(front.emitter->eval(hit, {0, 0, -1}), radiance, 0));
    EXPECT_TRUE(front.emitter->eval(hit, {0, 0, 1}).is_black());
    EXPECT_EQ(front.emitter->sample_direct(above, {0.3f, 0.4f}).pdf, 0.f);
}

/// Monte Carlo irradiance at `ref` (surface normal +z) from sample_direct: E = mean of
/// weight * cos(theta). Returns {mean, standard error}.
std::pair<double, double> irradiance(const Emitter& e, const Vec3& ref, int n, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> uni(0.f, 1.f);
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        const EmitterSample s = e.sample_direct(ref, {uni(rng), uni(rng)});
        const double x = s.pdf > 0 ? double(s.weight.r) * std::max(0.f, s.wi.z) : 0.0;
        sum += x;
        sum2 += x * x;
    }
    const double mean = sum / n;
    const double var = std::max(0.0, sum2 / n - mean * mean);
    return {mean, std::sqrt(var / (n - 1))};
}

TEST(EmitterArea, DiskIrradianceMatchesClosedForm) {
    // A disk of radius R at height h facing the point on its axis: E = pi L R^2 / (h^2 + R^2).
    // The fan has the disk's area and deviates from the circle by < 5.1e-5 R, which changes
    // E by far less than the 1e-4 relative bias allowed on top of 5 standard errors.
    const double R = 1.5, h = 2, L = 3;
    Properties disk("disk", {});
    disk.set_transform("to_world", Transform::translate({0, 0, float(h)}) *
                                       Transform::rotate({1, 0, 0}, 180) *
                                       Transform::scale({float(R), float(R), 1}));
    const Lit lit = area_light(disk, Color(float(L)));
    ASSERT_TRUE(lit.emitter && lit.shape);
    const auto [mean, se] = irradiance(*lit.emitter, Vec3(0.f), 40000, 1);
    const double expected = kPiD * L * R * R / (h * h + R * R);
    EXPECT_NEAR(mean, expected, 5 * se + 1e-4 * expected) << "standard error " << se;
    EXPECT_LT(se, 0.01 * expected);  // the check above is meaningful
}

TEST(EmitterArea, SphereIrradianceMatchesClosedForm) {
    // A sphere of radius R at distance d straight above the point: E = pi L (R / d)^2. The
    // host samples the visible cone; the estimator's variance comes from cos(theta) only.
    const double R = 0.5, d = 3, L = 2;
    Properties sphere("sphere", {});
    sphere.set_point("center", {0, 0, float(d)});
    sphere.set_float("radius", R);
    const Lit lit = area_light(sphere, Color(float(L)));
    ASSERT_TRUE(lit.emitter && lit.shape);
    const auto [mean, se] = irradiance(*lit.emitter, Vec3(0.f), 20000, 2);
    const double expected = kPiD * L * (R / d) * (R / d);
    EXPECT_NEAR(mean, expected, 5 * se + 1e-6 * expected) << "standard error " << se;
    EXPECT_LT(se, 0.01 * expected);
}

TEST(EmitterArea, NoShapeNoLight) {
    auto e = make_emitter(Properties("area", {}));
    ASSERT_TRUE(e);
    EXPECT_EQ(e->sample_direct({0, 0, 0}, {0.5f, 0.5f}).pdf, 0.f);
    Properties bad("area", {});
    bad.set_color("radiance", {1, -1, 1});
    EXPECT_NE(error_of(bad).find("radiance"), std::string::npos);
}

}  // namespace
