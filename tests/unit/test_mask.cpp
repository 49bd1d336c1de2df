// The `mask` material in renders: what is seen through and on a partially opaque surface, with
// a constant and a textured opacity, and its input errors. (Its sampling is in the BSDF chi2 and
// consistency matrices; the pass-through's timing in every integrator is the conformance check
// MaskPassesWithoutDelay.)
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "femto/host.h"
#include "femto/testing/render.h"
#include "scene_util.h"

namespace {

using femto::testing::MeanAndError;

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

/// Orthographic camera at height 5 looking down on [-1, 1]^2: res x res pixels, box filter.
std::string camera(int res, int spp) {
    return "<sensor type=\"orthographic\"><transform name=\"to_world\"><lookat origin=\"0,0,5\" "
           "target=\"0,0,0\" up=\"0,1,0\"/></transform><sampler type=\"independent\"><integer "
           "name=\"sample_count\" value=\"" +
           std::to_string(spp) + "\"/></sampler><film type=\"hdrfilm\"><integer name=\"width\" " +
           "value=\"" + std::to_string(res) + "\"/><integer name=\"height\" value=\"" +
           std::to_string(res) + "\"/><rfilter type=\"box\"/></film></sensor>";
}

/// View factor from a surface element at the origin (normal +z) to the rectangle [0, w] x
/// [0, l] parallel to it at height h (one corner above the element).
double corner_view_factor(double w, double l, double h) {
    const double X = w / h, Y = l / h, a = std::sqrt(1 + X * X), b = std::sqrt(1 + Y * Y);
    return (X / a * std::atan(Y / a) + Y / b * std::atan(X / b)) / (2 * M_PI);
}

/// View factor from the element at (x, y, 0) to the square [-s, s]^2 at height h: the sum over
/// the four corner rectangles that meet above the element.
double view_factor(double x, double y, double s, double h) {
    return corner_view_factor(s - x, s - y, h) + corner_view_factor(s + x, s - y, h) +
           corner_view_factor(s - x, s + y, h) + corner_view_factor(s + x, s + y, h);
}

// A mask of opacity alpha at z = 0 over a diffuse material of albedo rho, lit from above by a
// square emitter of radiance 1 and half-side s at height h (a `null` material, so the camera
// looks through its back), with an emitting plane of radiance 1 below it. A pixel sees
//   L = (1 - alpha) * 1 + alpha * rho * F(x, y),
// F the view factor to the square, averaged over the pixel (the box filter's footprint): the
// light below comes through the transparent part, the square's light off the opaque part. Each
// pixel is an independent estimate of its L, so L_p / expected_p are independent estimates of
// 1 whose mean has the standard error of their spread.
TEST(MaskRender, SeesThroughOneMinusOpacityPlusOpacityTimesReflection) {
    const int res = 8, spp = 256;
    const double alpha = 0.6, rho = 0.8, s = 2, h = 3;
    const std::string xml =
        "<scene version=\"3.0.0\"><integrator type=\"path\"><integer name=\"max_depth\" "
        "value=\"3\"/></integrator>" +
        camera(res, spp) +
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"" + num(s) +
        "\"/><rotate x=\"1\" angle=\"180\"/><translate z=\"" + num(h) +
        "\"/></transform><bsdf type=\"null\"/><emitter type=\"area\"><float name=\"radiance\" "
        "value=\"1\"/></emitter></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"1.5\"/>"
        "</transform><bsdf type=\"mask\"><float name=\"opacity\" value=\"" +
        num(alpha) + "\"/><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"" + num(rho) +
        "\"/></bsdf></bsdf></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/><translate "
        "z=\"-1\"/></transform><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0\"/>"
        "</bsdf><emitter type=\"area\"><float name=\"radiance\" value=\"1\"/></emitter></shape>"
        "</scene>";
    auto scene = femto::load_scene_string(xml);
    const std::vector<float> img = femto::testing::render_steady(*scene, 3);
    std::vector<double> ratio;
    for (int py = 0; py < res; ++py)
        for (int px = 0; px < res; ++px) {
            // F averaged over the pixel's footprint (F is symmetric in x and y, so the image's
            // orientation does not matter); 16 x 16 midpoints: error ~1e-6.
            double f = 0;
            for (int j = 0; j < 16; ++j)
                for (int i = 0; i < 16; ++i)
                    f += view_factor(-1 + (px + (i + 0.5) / 16) * 2.0 / res,
                                     -1 + (py + (j + 0.5) / 16) * 2.0 / res, s, h);
            f /= 256;
            const double expected = (1 - alpha) + alpha * rho * f;
            const size_t k = 3 * (size_t(py) * res + size_t(px));
            for (int c = 0; c < 3; ++c) EXPECT_EQ(img[k + size_t(c)], img[k]);  // grey
            ratio.push_back(img[k] / expected);
        }
    const MeanAndError m = femto::testing::mean_and_error(ratio);
    std::printf("[mask] seen / ((1 - a) + a rho F): %.5f +- %.5f\n", m.mean, m.standard_error);
    EXPECT_GT(m.standard_error, 0);
    EXPECT_NEAR(m.mean, 1.0, 4 * m.standard_error);
}

// A checkerboard opacity (0.2 and 0.7) over the same view of an emitter: each quadrant of the
// image passes 1 - its opacity (a binomial proportion over its 16 x spp camera samples), the
// two diagonals alike.
TEST(MaskRender, CheckerboardOpacityTexture) {
    const int res = 8, spp = 64;
    const double a0 = 0.2, a1 = 0.7;
    const std::string xml =
        "<scene version=\"3.0.0\"><integrator type=\"path\"><integer name=\"max_depth\" "
        "value=\"3\"/></integrator>" +
        camera(res, spp) +
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/>"
        "</transform><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0\"/></bsdf>"
        "<emitter type=\"area\"><float name=\"radiance\" value=\"1\"/></emitter></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><translate z=\"2.5\"/>"
        "</transform><bsdf type=\"mask\"><texture type=\"checkerboard\" name=\"opacity\">"
        "<float name=\"color0\" value=\"" +
        num(a0) + "\"/><float name=\"color1\" value=\"" + num(a1) +
        "\"/></texture><bsdf type=\"diffuse\"/></bsdf></shape></scene>";
    auto scene = femto::load_scene_string(xml);
    const std::vector<float> img = femto::testing::render_steady(*scene, 5);
    double q[2][2] = {{0, 0}, {0, 0}};
    for (int py = 0; py < res; ++py)
        for (int px = 0; px < res; ++px)
            q[py / (res / 2)][px / (res / 2)] += img[3 * (size_t(py) * res + size_t(px))] / 16.0;
    const double n = 16.0 * spp;
    const auto tol = [&](double a) { return 4 * std::sqrt(a * (1 - a) / n); };
    // Which diagonal holds color0 depends on the camera's orientation; the same on both.
    const bool first_is_0 = std::abs(q[0][0] - (1 - a0)) < std::abs(q[0][0] - (1 - a1));
    const double d0 = first_is_0 ? a0 : a1, d1 = first_is_0 ? a1 : a0;
    std::printf("[mask] checkerboard quadrants: %.4f %.4f / %.4f %.4f (expected %.2f, %.2f)\n",
                q[0][0], q[0][1], q[1][0], q[1][1], 1 - d0, 1 - d1);
    EXPECT_NEAR(q[0][0], 1 - d0, tol(d0));
    EXPECT_NEAR(q[1][1], 1 - d0, tol(d0));
    EXPECT_NEAR(q[0][1], 1 - d1, tol(d1));
    EXPECT_NEAR(q[1][0], 1 - d1, tol(d1));
}

// The time integral of a transient render of a scene with a mask (seen through, lit, with a
// checkerboard opacity) is the steady render with the same seed, for a camera-path, a
// bidirectional and a light-tracing integrator: the same random numbers, so the images agree to
// float rounding (the cube sums per bin in float, hdrfilm in double), given a window [0, 50)
// that holds every path (the camera segment is about 5, further ones a few units each and
// max_depth 6 bounds them).
TEST(MaskRender, TimeIntegralIsTheSteadyImage) {
    const std::string body =
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2\"/><rotate "
        "x=\"1\" angle=\"180\"/><translate z=\"3\"/></transform><bsdf type=\"null\"/><emitter "
        "type=\"area\"><float name=\"radiance\" value=\"1\"/></emitter></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"1.5\"/>"
        "</transform><bsdf type=\"mask\"><texture type=\"checkerboard\" name=\"opacity\">"
        "<float name=\"color0\" value=\"0.3\"/><float name=\"color1\" value=\"0.8\"/>"
        "</texture><bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf></bsdf></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/><translate "
        "z=\"-1\"/></transform><bsdf type=\"diffuse\"/><emitter type=\"area\"><float "
        "name=\"radiance\" value=\"0.5\"/></emitter></shape>";
    const auto scene = [&](const std::string& integrator, const std::string& film) {
        return "<scene version=\"3.0.0\"><integrator type=\"" + integrator +
               "\"><integer name=\"max_depth\" value=\"6\"/></integrator><sensor "
               "type=\"perspective\"><float name=\"fov\" value=\"30\"/><transform "
               "name=\"to_world\"><lookat origin=\"0,0,5\" target=\"0,0,0\" "
               "up=\"0,1,0\"/></transform><sampler type=\"independent\"><integer "
               "name=\"sample_count\" value=\"8\"/></sampler>" +
               film + "</sensor>" + body + "</scene>";
    };
    const std::string size =
        "<integer name=\"width\" value=\"8\"/><integer name=\"height\" value=\"8\"/>";
    const std::string transient = "<film type=\"transient\">" + size +
                                  "<float name=\"start\" value=\"0\"/><float "
                                  "name=\"bin_width\" value=\"0.25\"/><integer name=\"bins\" "
                                  "value=\"200\"/><rfilter type=\"box\"/></film>";
    const std::string steady = "<film type=\"hdrfilm\">" + size + "<rfilter type=\"box\"/></film>";
    for (const char* integrator : {"transient_path", "transient_bdpt", "transient_light"}) {
        SCOPED_TRACE(integrator);
        auto t = femto::load_scene_string(scene(integrator, transient));
        auto s = femto::load_scene_string(scene(integrator, steady));
        femto::testing::expect_same_image(femto::testing::render_steady(*t, 17),
                                          femto::testing::render_steady(*s, 17),
                                          "cube summed over time", "steady");
    }
}

std::string mask_scene(const std::string& mask_body) {
    return femto::test::scene_xml("<shape type=\"rectangle\">\n<bsdf type=\"mask\">\n" + mask_body +
                                  "\n</bsdf></shape>");
}

TEST(MaskErrors, OpacityOutsideZeroOneOrNotANumberIsLocated) {
    for (const char* v : {"1.5", "-0.25", "nan"}) {
        const std::string msg = femto::test::load_error(mask_scene(
            std::string("<float name=\"opacity\" value=\"") + v + "\"/><bsdf type=\"diffuse\"/>"));
        EXPECT_NE(msg.find("opacity"), std::string::npos) << v << ": " << msg;
        EXPECT_NE(msg.find("<string>:5:"), std::string::npos) << v << ": " << msg;
    }
    const std::string rgb = femto::test::load_error(
        mask_scene("<rgb name=\"opacity\" value=\"0.5, 1.2, 0.5\"/><bsdf type=\"diffuse\"/>"));
    EXPECT_NE(rgb.find("[0, 1]"), std::string::npos) << rgb;
}

TEST(MaskErrors, NeedsExactlyOneNestedMaterial) {
    const std::string none = femto::test::load_error(mask_scene(""));
    EXPECT_NE(none.find("exactly one nested <bsdf>"), std::string::npos) << none;
    EXPECT_NE(none.find("<string>:4:"), std::string::npos) << none;
    const std::string two =
        femto::test::load_error(mask_scene("<bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/>"));
    EXPECT_NE(two.find("2 were given"), std::string::npos) << two;
    const std::string fluo = femto::test::load_error(mask_scene("<bsdf type=\"fluorescent\"/>"));
    EXPECT_NE(fluo.find("vertex event"), std::string::npos) << fluo;
}

// Mitsuba 0.6 spells the opacity as a <spectrum>.
TEST(MaskRender, LoadsMitsuba06Spectrum) {
    auto scene = femto::load_scene_string(femto::test::scene_xml(
        "<shape type=\"rectangle\"><bsdf type=\"mask\"><spectrum name=\"opacity\" "
        "value=\"0.25\"/><bsdf type=\"diffuse\"/></bsdf></shape>",
        "0.6.0"));
    EXPECT_TRUE(scene);
}

}  // namespace
