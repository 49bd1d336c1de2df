// Mitsuba 0.6's infinitely thin `collimated` beam (no radius): a single ray carrying its power,
// seen only through light paths. In fog, its single-scattered light on a pinhole camera's film
// matches a closed form, and agrees with femto's beam of a small radius and the same power.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "agreement_util.h"
#include "femto/scene.h"
#include "scene_util.h"

namespace femto {
namespace {

// A beam of power 1 leaves x = -3 along +x and crosses, from x = -2 to 2, a box of fog
// (sigma_s 0.15, sigma_a 0.05, isotropic) x in [-2, 2], y and z in [-1, 1] behind null walls.
// A pinhole camera at (0, y_c, z_c) looks down -z with a 60 degree field of view on a W x W
// film; y_c is half a pixel at the beam's depth (tan 30 deg z_c / W), so that the beam crosses
// the middle of a row of pixels, not the edge between two rows (which a thin beam would light
// on one side only and a wide one on both).
constexpr double kSigmaS = 0.15, kSigmaT = 0.2, kFov = 60;
constexpr double kPiD = 3.14159265358979323846;
constexpr int kRes = 32;

double tan_half_fov() { return std::tan(kFov / 2 * kPiD / 180); }

double camera_y(double camera_z) { return tan_half_fov() * camera_z / kRes; }

std::string beam_in_fog(const std::string& integrator, const std::string& beam, int spp,
                        double camera_z = 5) {
    const std::string y = test::xml_number(camera_y(camera_z));
    return test::scene_xml(
        "<medium type=\"homogeneous\" id=\"fog\"><float name=\"sigma_s\" value=\"" +
        test::xml_number(kSigmaS) + "\"/><float name=\"sigma_a\" value=\"" +
        test::xml_number(kSigmaT - kSigmaS) +
        "\"/></medium>"
        "<integrator type=\"" +
        integrator +
        "\"><integer name=\"max_depth\" value=\"2\"/></integrator>"
        "<sensor type=\"perspective\"><float name=\"fov\" value=\"" +
        test::xml_number(kFov) + "\"/><transform name=\"to_world\"><lookat origin=\"0," + y + "," +
        test::xml_number(camera_z) + "\" target=\"0," + y + ",0\" up=\"0,1,0\"/></transform>" +
        test::independent_sampler(spp) + "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" +
        std::to_string(kRes) + "\"/><integer name=\"height\" value=\"" + std::to_string(kRes) +
        "\"/><rfilter type=\"box\"/></film></sensor>"
        "<shape type=\"cube\"><transform name=\"to_world\"><scale x=\"2\" y=\"1\" z=\"1\"/>"
        "</transform><bsdf type=\"null\"/><ref name=\"interior\" id=\"fog\"/></shape>"
        "<emitter type=\"collimated\"><transform name=\"to_world\"><lookat origin=\"-3,0,0\" "
        "target=\"0,0,0\" up=\"0,1,0\"/></transform>" +
        beam + "<float name=\"power\" value=\"1\"/></emitter>");
}

// The film's pixels times their area on the image plane at unit distance (side 2 tan(fov / 2)
// / W) integrate the radiance over that plane, which for a point source of intensity I at
// distance d seen at angle theta off the axis is I / (d^2 cos^3 theta) (the plane's element is
// dw / cos^3 theta). The beam's element dx at (x, 0, 0) scatters I = e^(-sigma_t (x + 2))
// sigma_s / (4 pi) dx toward the camera at (0, y_c, z_c), attenuated by e^(-sigma_t d / z_c)
// on the way out through the top (z = 1, a z_c-th of the way); cos theta = z_c / d. The
// camera sees the beam where |x| <= z_c tan(fov / 2).
double closed_form_film_integral(double camera_z = 5) {
    const double reach = std::min(2.0, camera_z * tan_half_fov()), y = camera_y(camera_z);
    const int steps = 200000;
    double sum = 0;
    for (int i = 0; i < steps; ++i) {
        const double x = -reach + 2 * reach * (i + 0.5) / steps;
        const double d = std::sqrt(x * x + y * y + camera_z * camera_z);
        const double cos3 = std::pow(camera_z / d, 3);
        sum += std::exp(-kSigmaT * (x + 2 + d / camera_z)) * kSigmaS / (4 * kPiD) / (d * d * cos3);
    }
    return sum * 2 * reach / steps;
}

struct Runs {
    std::vector<testing::Cube> images;
    testing::MeanAndError film_integral;
};

Runs render_beam(const std::string& xml, int runs, uint64_t seed) {
    Runs out;
    const double side = 2 * tan_half_fov() / kRes;
    std::vector<double> totals;
    for (int r = 0; r < runs; ++r) {
        auto scene = load_scene_string(xml);
        testing::Cube c;
        c.H = c.W = kRes, c.T = 1, c.C = 3;
        c.data = testing::render_steady(*scene, seed + uint64_t(r));
        double total = 0;
        for (size_t i = 0; i < c.data.size(); i += 3) total += c.data[i];
        totals.push_back(total * side * side);
        out.images.push_back(std::move(c));
    }
    out.film_integral = testing::mean_and_error(totals);
    return out;
}

TEST(LightTracer, ThinCollimatedBeamInFogMatchesClosedForm) {
    constexpr int kRuns = 16;
    const double expected = closed_form_film_integral();
    const Runs thin = render_beam(beam_in_fog("transient_light", "", 16), kRuns, 1);
    // A beam of radius 0.002 differs from the thin one by O(r^2) in this integral.
    const Runs finite = render_beam(
        beam_in_fog("transient_light", "<float name=\"radius\" value=\"0.002\"/>", 16), kRuns, 101);
    std::printf("film integral: thin %.6g +- %.2g, radius 0.002 %.6g +- %.2g, closed form %.6g\n",
                thin.film_integral.mean, thin.film_integral.standard_error,
                finite.film_integral.mean, finite.film_integral.standard_error, expected);
    EXPECT_NEAR(thin.film_integral.mean, expected, 4 * thin.film_integral.standard_error);
    EXPECT_NEAR(finite.film_integral.mean, expected, 4 * finite.film_integral.standard_error);
    EXPECT_LT(thin.film_integral.standard_error, 0.01 * expected);
    // Pixel by pixel, the thin beam is the limit of the finite one.
    test::expect_agree(test::cells_of(thin.images, 1, 1), test::cells_of(finite.images, 1, 1),
                       kRuns, "thin vs radius 0.002 beam");
}

// BDPT starts light paths from the thin beam too; strategies connecting to its start are
// impossible and leave the MIS weights, so its image integrates to the same closed form. The
// camera close above the fog (z = 1.3) makes the camera's density of a beam point comparable
// to the light's, so that weighing in the impossible strategy would lose a visible share.
TEST(LightTracer, ThinCollimatedBeamUnderBdptMatchesClosedForm) {
    for (const double camera_z : {5.0, 1.3}) {
        const Runs bdpt = render_beam(beam_in_fog("transient_bdpt", "", 8, camera_z), 12, 7);
        const double expected = closed_form_film_integral(camera_z);
        std::printf("bdpt film integral (camera at z = %g): %.6g +- %.2g, closed form %.6g\n",
                    camera_z, bdpt.film_integral.mean, bdpt.film_integral.standard_error, expected);
        EXPECT_NEAR(bdpt.film_integral.mean, expected, 4 * bdpt.film_integral.standard_error);
        EXPECT_LT(bdpt.film_integral.standard_error, 0.02 * expected);
    }
}

// A path tracer cannot see the thin beam (as in Mitsuba): its image is black.
TEST(LightTracer, ThinCollimatedBeamIsInvisibleToPathTracers) {
    auto scene = load_scene_string(beam_in_fog("path", "", 4));
    const std::vector<float> img = testing::render_steady(*scene, 3);
    double total = 0;
    for (float v : img) total += v;
    EXPECT_EQ(total, 0.0);
}

}  // namespace
}  // namespace femto
