// Numerical stress (issue 12 §3): extreme parameters either render correctly or are refused
// with a located error, and never put a NaN, an infinite or a negative value into a film (every
// render here asserts the film refused nothing). Scale invariance from 1e-6 to 1e6 is in
// test_scale.cpp and the conformance matrix.
//  - time bins of 1e-6 of the scene's size, 1e5 of them: the arrival lands in its exact bin;
//  - extinction from 1e-6 to 1e6: an absorbing ball's transmittance against exp(-sigma_t 2R),
//    and scattering balls (albedo 0.9 and 1, no depth limit: the film's window ends paths)
//    with every integrator;
//  - grazing angles (camera and light 1e-3 rad above a plane);
//  - a mesh light with a degenerate triangle renders as without it; a light of zero area is
//    refused.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cube_util.h"
#include "femto/host.h"
#include "femto/scene.h"
#include "femto/sensor.h"
#include "scene_util.h"

using namespace femto;
using namespace femto::test;

namespace {

std::string radiancemeter(const std::string& origin, const std::string& direction, int spp,
                          const std::string& film) {
    return "<sensor type=\"radiancemeter\"><point name=\"origin\" value=\"" + origin +
           "\"/><vector name=\"direction\" value=\"" + direction + "\"/>" +
           independent_sampler(spp) + film + "</sensor>";
}

// Renders with `seed` and checks that the film refused nothing and holds only finite values.
Cube render_checked(Scene& scene, uint64_t seed) {
    const Cube cube = render_cube(scene, seed, "stress");
    const RejectedContributions r = scene.sensor().film().rejected();
    EXPECT_EQ(r.total(), 0u) << r.nan << " NaN, " << r.infinite << " infinite, " << r.negative
                             << " negative";
    for (const float v : cube.data) {
        EXPECT_TRUE(std::isfinite(v) && v >= 0) << v;
        if (!(std::isfinite(v) && v >= 0)) break;
    }
    return cube;
}

double cube_sum(const Cube& cube) {
    double s = 0;
    for (const float v : cube.data) s += v;
    return s;
}

}  // namespace

// A radiance meter 3 above a Lambertian plane, looking down at (0.5, 0, 0) lit by a point light
// at (0, 0, 1.5): the light arrives at camera time t = 3 + sqrt(2.5). The film has 1e5 bins of
// 1e-6 (a third of a millionth of the scene's size), placed so that t falls in the middle of
// bin 81138; that bin holds the whole radiance (0.6 / pi) I cos / r^2 and no other bin any.
TEST(Stress, MicroscopicBinsCatchTheArrivalInItsBin) {
    const double t = 3 + std::sqrt(2.5), width = 1e-6,
                 L = 0.6 / M_PI * 5 * (1.5 / std::sqrt(2.5)) / 2.5;
    const int bins = 100000, bin = 81138;
    const std::string body =
        radiancemeter("0.5,0,3", "0,0,-1", 4,
                      box_transient_film(1, 1, t - (bin + 0.5) * width, width, bins)) +
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"10\"/></transform>"
        "<bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0.6\"/></bsdf></shape>"
        "<emitter type=\"point\"><point name=\"position\" value=\"0,0,1.5\"/><float "
        "name=\"intensity\" value=\"5\"/></emitter>";
    for (const char* integrator : {"transient_path", "transient_bdpt"}) {
        SCOPED_TRACE(integrator);
        auto scene = load_scene_string("<scene version=\"3.0.0\"><integrator type=\"" +
                                       std::string(integrator) + "\"/>" + body + "</scene>");
        const Cube cube = render_checked(*scene, 1);
        ASSERT_EQ(cube.T, bins);
        EXPECT_NEAR(cube.at(0, 0, bin, 0), L, 1e-5 * L);
        EXPECT_NEAR(cube_sum(cube), 3 * L, 3e-5 * L);  // three channels, all in that bin
    }
}

// A ball of radius 1 of a purely absorbing medium between a radiance meter and a light of
// radiance 1: the meter reads exp(-2 sigma_t), for sigma_t from 1e-6 (the ball is nearly
// vacuum) to 1e6 (nothing passes; exp underflows to 0). Checked against eight seeds' spread
// (plus 1e-5 for the nearly transparent case, where every sample passes and the spread is 0).
TEST(Stress, AbsorbingBallTransmitsExpMinusTwoSigmaAtEveryExtinction) {
    for (const double sigma : {1e-6, 1e-3, 1.0, 1e3, 1e6}) {
        for (const char* integrator : {"transient_path", "transient_bdpt"}) {
            SCOPED_TRACE(std::string(integrator) + " sigma_t " + xml_number(sigma));
            const std::string xml =
                "<scene version=\"3.0.0\"><medium type=\"homogeneous\" id=\"ink\"><float "
                "name=\"sigma_t\" value=\"" +
                xml_number(sigma) +
                "\"/><float name=\"albedo\" value=\"0\"/></medium><integrator type=\"" +
                integrator + "\"/>" +
                radiancemeter("0,0,3", "0,0,-1", 256, box_transient_film(1, 1, 0, 0.5, 20)) +
                "<shape type=\"sphere\"><bsdf type=\"null\"/><ref name=\"interior\" "
                "id=\"ink\"/></shape>"
                "<shape type=\"rectangle\"><transform name=\"to_world\"><scale "
                "value=\"3\"/><translate "
                "z=\"-3\"/></transform><emitter type=\"area\"/></shape></scene>";
            std::vector<double> reads;
            for (uint64_t seed = 1; seed <= 8; ++seed) {
                auto scene = load_scene_string(xml);
                reads.push_back(cube_sum(render_checked(*scene, seed)) / 3);
            }
            const auto [mean, error] = femto::testing::mean_and_error(reads);
            const double expected = std::exp(-2 * sigma);
            EXPECT_NEAR(mean, expected, 5 * error + 1e-5 * expected) << "+- " << error;
        }
    }
}

// Scattering balls of extinction 1e3 and 1e6 (mean free paths 1e-3 and 1e-6 of the ball's
// radius), albedo 0.9 and 1, no depth limit and no Russian roulette: the film's time window
// alone ends the paths. Every integrator finishes, and its film holds finite light only.
TEST(Stress, DenseScatteringWithoutDepthLimitEndsAtTheWindow) {
    for (const double sigma : {1e3, 1e6})
        for (const char* albedo : {"0.9", "1"})
            for (const char* integrator : {"transient_path", "transient_bdpt", "transient_light"}) {
                SCOPED_TRACE(std::string(integrator) + " sigma_t " + xml_number(sigma) +
                             " albedo " + albedo);
                auto scene = load_scene_string(
                    "<scene version=\"3.0.0\"><medium type=\"homogeneous\" id=\"fog\"><float "
                    "name=\"sigma_t\" value=\"" +
                    xml_number(sigma) + "\"/><float name=\"albedo\" value=\"" + albedo +
                    "\"/></medium><integrator type=\"" + integrator +
                    "\"><integer name=\"max_depth\" value=\"-1\"/></integrator><sensor "
                    "type=\"perspective\"><transform name=\"to_world\"><lookat origin=\"0,0,6\" "
                    "target=\"0,0,0\" up=\"0,1,0\"/></transform>" +
                    independent_sampler(2) + box_transient_film(8, 8, 3, 0.1, 100) +
                    "</sensor><shape type=\"sphere\"><bsdf type=\"null\"/><ref name=\"interior\" "
                    "id=\"fog\"/></shape><shape type=\"rectangle\"><transform "
                    "name=\"to_world\"><scale value=\"3\"/><translate z=\"-3\"/></transform>"
                    "<emitter type=\"area\"/></shape></scene>");
                const Cube cube = render_checked(*scene, 1);
                EXPECT_GT(cube_sum(cube), 0.0);  // the light around the ball
            }
}

// Camera and point light 1e-3 above a plane 10 apart: every ray meets the plane at a grazing
// angle of about 2e-4 rad. Every integrator renders finite light.
TEST(Stress, GrazingAnglesStayFinite) {
    for (const char* integrator : {"transient_path", "transient_bdpt", "transient_light"}) {
        SCOPED_TRACE(integrator);
        auto scene = load_scene_string(
            "<scene version=\"3.0.0\"><integrator type=\"" + std::string(integrator) +
            "\"/><sensor type=\"perspective\"><float name=\"fov\" value=\"10\"/><transform "
            "name=\"to_world\"><lookat origin=\"0,0.001,5\" target=\"0,0,-5\" up=\"0,1,0\"/>"
            "</transform>" +
            independent_sampler(16) + box_transient_film(8, 8, 0, 0.5, 60) +
            "</sensor><shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"10\"/>"
            "<rotate x=\"1\" angle=\"-90\"/></transform></shape><emitter type=\"point\"><point "
            "name=\"position\" value=\"0,0.001,-5\"/><float name=\"intensity\" value=\"100\"/>"
            "</emitter></scene>");
        const Cube cube = render_checked(*scene, 1);
        EXPECT_GT(cube_sum(cube), 0.0);
    }
}

// A mesh light with a degenerate (zero-area) triangle renders exactly as the same light without
// it (it is never sampled and never hit); a mesh light whose every triangle is degenerate has
// no area to emit from and is refused.
TEST(Stress, DegenerateTrianglesAndZeroAreaLights) {
    const auto dir = femto::testing::temp_dir("stress-degenerate");
    std::ofstream(dir / "good.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    std::ofstream(dir / "mixed.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 4\nf 1 2 3\n";
    std::ofstream(dir / "flat.obj") << "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n";
    auto xml = [&](const std::string& mesh) {
        return "<scene version=\"3.0.0\"><integrator type=\"transient_path\"/><sensor "
               "type=\"perspective\"><transform name=\"to_world\"><lookat origin=\"0.3,0.3,3\" "
               "target=\"0.3,0.3,0\" up=\"0,1,0\"/></transform>" +
               independent_sampler(16) + box_transient_film(8, 8, 0, 0.5, 20) +
               "</sensor><shape type=\"obj\"><string name=\"filename\" value=\"" +
               (dir / mesh).string() +
               "\"/><emitter type=\"area\"/></shape><shape type=\"rectangle\"><transform "
               "name=\"to_world\"><scale value=\"3\"/><translate z=\"-1\"/></transform></shape>"
               "</scene>";
    };
    auto good = load_scene_string(xml("good.obj"));
    auto mixed = load_scene_string(xml("mixed.obj"));
    const Cube a = render_checked(*good, 5), b = render_checked(*mixed, 5);
    EXPECT_GT(cube_sum(a), 0.0);
    EXPECT_NEAR(cube_sum(b), cube_sum(a), 1e-5 * cube_sum(a));
    EXPECT_NE(load_error(xml("flat.obj")).find("zero surface area"), std::string::npos);
    std::filesystem::remove_all(dir);
}
