// Tests of the reconstruction filter plugins (box, tent, gaussian): Mitsuba's definitions,
// values at the centre and the radius, support, symmetry and the integral of each filter.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "femto/host.h"
#include "femto/rfilter.h"
#include "femto/scene.h"
#include "femto/sensor.h"

namespace {

using femto::PluginKind;
using femto::Properties;
using femto::ReconstructionFilter;

std::shared_ptr<ReconstructionFilter> make_filter(const std::string& type,
                                                  const char* param = nullptr, double value = 0.0) {
    Properties props(type, {});
    if (param) props.set_float(param, value);
    femto::ObjectPtr obj = femto::create_object(PluginKind::ReconstructionFilter, type, props);
    EXPECT_TRUE(obj);
    EXPECT_EQ(obj->kind(), PluginKind::ReconstructionFilter);
    return std::static_pointer_cast<ReconstructionFilter>(obj);
}

/// Midpoint-rule integral of the filter over [-radius - 1, radius + 1] (also checks that the
/// filter is 0 outside its radius and symmetric).
double integral(const ReconstructionFilter& f) {
    const double r = f.radius();
    const double lo = -r - 1.0, hi = r + 1.0;
    constexpr int kSteps = 400000;
    const double h = (hi - lo) / kSteps;
    double sum = 0.0;
    for (int i = 0; i < kSteps; ++i) {
        const double x = lo + (i + 0.5) * h;
        const float w = f.eval(static_cast<float>(x));
        EXPECT_GE(w, 0.f) << x;
        if (std::abs(x) > r) {
            EXPECT_EQ(w, 0.f) << "outside the radius at " << x;
        }
        sum += w;
    }
    return sum * h;
}

TEST(RFilterBox, MitsubaBox) {
    auto f = make_filter("box");
    EXPECT_EQ(f->radius(), 0.5f);
    EXPECT_EQ(f->eval(0.f), 1.f);
    EXPECT_EQ(f->eval(0.49f), 1.f);
    EXPECT_EQ(f->eval(-0.49f), 1.f);
    // Half-open support: a sample on a pixel boundary belongs to exactly one pixel, the one
    // whose samples lie in [i, i + 1): at position i exactly, offset centre - position = 0.5.
    EXPECT_EQ(f->eval(0.5f), 1.f);
    EXPECT_EQ(f->eval(-0.5f), 0.f);
    EXPECT_EQ(f->eval(0.7f), 0.f);
    EXPECT_EQ(f->eval(-3.f), 0.f);
    EXPECT_NEAR(integral(*f), 1.0, 1e-4);
}

TEST(RFilterTent, DefaultAndCustomRadius) {
    auto f = make_filter("tent");
    EXPECT_EQ(f->radius(), 1.f);
    EXPECT_EQ(f->eval(0.f), 1.f);
    EXPECT_FLOAT_EQ(f->eval(0.5f), 0.5f);
    EXPECT_FLOAT_EQ(f->eval(-0.25f), 0.75f);
    EXPECT_EQ(f->eval(1.f), 0.f);
    EXPECT_EQ(f->eval(-1.f), 0.f);
    EXPECT_EQ(f->eval(1.5f), 0.f);
    EXPECT_NEAR(integral(*f), 1.0, 1e-6);  // integral of a tent = its radius

    auto g = make_filter("tent", "radius", 2.5);
    EXPECT_EQ(g->radius(), 2.5f);
    EXPECT_EQ(g->eval(0.f), 1.f);
    EXPECT_FLOAT_EQ(g->eval(1.f), 0.6f);
    EXPECT_FLOAT_EQ(g->eval(-2.f), 0.2f);
    EXPECT_EQ(g->eval(2.5f), 0.f);
    EXPECT_NEAR(integral(*g), 2.5, 1e-5);
}

TEST(RFilterTent, RejectsNonPositiveRadius) {
    for (double bad : {0.0, -1.0}) {
        Properties props("tent", {});
        props.set_float("radius", bad);
        EXPECT_THROW(femto::create_object(PluginKind::ReconstructionFilter, "tent", props),
                     femto::SceneError);
    }
}

/// The truncated Gaussian of Mitsuba 3, in double precision.
double gaussian_ref(double x, double s) {
    const double r = 4.0 * s;
    if (std::abs(x) > r) return 0.0;
    return std::max(0.0, std::exp(-x * x / (2 * s * s)) - std::exp(-r * r / (2 * s * s)));
}

TEST(RFilterGaussian, TruncatedAndShiftedAsMitsuba) {
    for (double s : {0.5, 0.3, 1.25}) {
        SCOPED_TRACE("stddev " + std::to_string(s));
        auto f = (s == 0.5) ? make_filter("gaussian") : make_filter("gaussian", "stddev", s);
        const double r = 4.0 * s;
        EXPECT_FLOAT_EQ(f->radius(), static_cast<float>(r));
        const double bias = std::exp(-8.0);  // the Gaussian's value at 4 stddev
        EXPECT_NEAR(f->eval(0.f), 1.0 - bias, 1e-6);
        EXPECT_NEAR(f->eval(static_cast<float>(s)), std::exp(-0.5) - bias, 1e-6);
        // Continuous at the radius (reaches 0 there), 0 beyond.
        EXPECT_NEAR(f->eval(static_cast<float>(r)), 0.0, 1e-6);
        EXPECT_NEAR(f->eval(static_cast<float>(0.999 * r)), 0.0, 1e-5);
        EXPECT_EQ(f->eval(static_cast<float>(1.01 * r)), 0.f);
        EXPECT_EQ(f->eval(static_cast<float>(-1.5 * r)), 0.f);
        float prev = f->eval(0.f);
        for (int i = 1; i <= 100; ++i) {
            const double x = r * i / 100.0;
            const float w = f->eval(static_cast<float>(x));
            EXPECT_NEAR(w, gaussian_ref(x, s), 1e-6) << x;
            EXPECT_EQ(w, f->eval(static_cast<float>(-x)));
            EXPECT_LE(w, prev);
            prev = w;
        }
        // Integral: s sqrt(2 pi) erf(4 / sqrt 2) - 2 r exp(-8).
        const double expected =
            s * std::sqrt(2.0 * std::numbers::pi) * std::erf(4.0 / std::sqrt(2.0)) - 2.0 * r * bias;
        EXPECT_NEAR(integral(*f), expected, 1e-5 * expected);
    }
}

TEST(RFilterGaussian, RejectsNonPositiveStddev) {
    for (double bad : {0.0, -0.5}) {
        Properties props("gaussian", {});
        props.set_float("stddev", bad);
        EXPECT_THROW(femto::create_object(PluginKind::ReconstructionFilter, "gaussian", props),
                     femto::SceneError);
    }
}

TEST(RFilterSchema, ParametersAreDocumented) {
    const std::pair<const char*, std::set<std::string>> expected[] = {
        {"box", {}}, {"tent", {"radius"}}, {"gaussian", {"stddev"}}};
    for (const auto& [type, params] : expected) {
        const femto::PluginDescriptor& d =
            femto::find_plugin(PluginKind::ReconstructionFilter, type);
        std::set<std::string> names;
        for (const auto& p : d.params) names.insert(p.name);
        EXPECT_EQ(names, params) << type;
        // A parameter a filter does not have is an error, not silently ignored.
        Properties props(type, {});
        props.set_float("radiuss", 1.0);
        EXPECT_THROW(femto::create_object(PluginKind::ReconstructionFilter, type, props),
                     femto::SceneError)
            << type;
    }
}

}  // namespace

namespace {

// Regression: `ldsampler` at 1 spp gives some pixels a jitter of exactly 0 (4 of 512 x 512 at
// seed 0), a sample on the pixel's lower edge. With the box filter's support the wrong way
// round it went to the pixel above, leaving its own black. Every pixel of an orthographic view
// of an emitting rectangle must read its radiance.
TEST(RFilterBox, EveryPixelKeepsItsOwnSample) {
    const std::string xml =
        "<scene version=\"3.0.0\"><integrator type=\"direct\"/><sensor type=\"orthographic\">"
        "<transform name=\"to_world\"><lookat origin=\"0, 0, 5\" target=\"0, 0, 0\" up=\"0, 1, "
        "0\"/></transform><sampler type=\"ldsampler\"><integer name=\"sample_count\" "
        "value=\"1\"/></sampler><film type=\"hdrfilm\"><integer name=\"width\" value=\"512\"/>"
        "<integer name=\"height\" value=\"512\"/><rfilter type=\"box\"/></film></sensor>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2\"/></transform>"
        "<emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape></scene>";
    const auto scene = femto::load_scene_string(xml);
    femto::RenderOptions opt;
    femto::render(*scene, opt);
    const std::vector<float> image = scene->sensor().film().steady_image();
    int wrong = 0;
    for (size_t i = 0; i < image.size(); ++i)
        if (image[i] != 1.f && ++wrong <= 5) ADD_FAILURE() << "pixel " << i / 3 << ": " << image[i];
    EXPECT_EQ(wrong, 0);
}

}  // namespace
