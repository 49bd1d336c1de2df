// transient_light (issue 11): light tracing splatted onto the film.
//  - agreement with transient_path per pixel block and per time group on the shipped scenes
//    (cornell-box, spheres, tof-plane seen by a perspective camera, fluorescent, fog-point,
//    fog-object): a chi-square over cells whose variances come from independent renders;
//  - the arrival on tof-plane is exact, the glass-slab delay is exact (light through glass),
//    and splats conserve energy under the kernel temporal filter;
//  - renders are bit-identical for a seed at 1 and 2 threads;
//  - bad input (an orthographic sensor, max_depth 0, the variance AOV) is a located error.
// The light tracer's connections and emission sampling are checked against their densities in
// test_emitters.cpp (EmissionSampling.*) and SensorConnection.* below.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "agreement_util.h"
#include "cube_util.h"
#include "femto/bsdf.h"
#include "femto/host.h"
#include "femto/sensor.h"
#include "scene_util.h"

using namespace femto;
using femto::test::Cube;
using namespace femto::test;

TEST(LightTracer, AgreesWithPathTracerOnCornellBox) {
    check_agreement({"cornell-box", 0, false, {{"res", "16"}, {"bins", "128"}}, 16, 16, 2, 16});
}

TEST(LightTracer, AgreesWithPathTracerOnSpheres) {
    check_agreement({"spheres", 0, false, {{"res", "16"}, {"bins", "160"}}, 16, 32, 2, 16});
}

TEST(LightTracer, AgreesWithPathTracerOnTofPlane) {
    check_agreement({"tof-plane", 2, true, {{"res", "16"}}, 4, 16, 2, 8});
}

TEST(LightTracer, AgreesWithPathTracerOnTofPlaneInWorldTime) {
    check_agreement({"tof-plane",
                     2,
                     true,
                     {{"res", "16"}, {"world_time", "true"}, {"start", "1.4"}},
                     4,
                     16,
                     2,
                     8});
}

TEST(LightTracer, AgreesWithPathTracerOnFluorescent) {
    check_agreement({"fluorescent", 0, true, {{"res", "16"}, {"bins", "150"}}, 16, 32, 2, 10});
}

TEST(LightTracer, AgreesWithPathTracerOnFogPoint) {
    check_agreement({"fog-point", 0, false, {{"res", "16"}, {"bins", "40"}}, 256, 32, 2, 5});
}

TEST(LightTracer, AgreesWithPathTracerOnFogObject) {
    check_agreement({"fog-object", 0, true, {{"res", "16"}, {"bins", "80"}}, 16, 32, 2, 8});
}

namespace {

// A point light of intensity 5 at height 1.5 over a Lambertian plane (albedo 0.6), seen by a
// pinhole camera at height 5 covering [-2, 2]^2 of the plane (tof-plane through a pinhole),
// with `slab` between them and the film `film`.
std::string pinhole_tof_plane(const std::string& film, const std::string& extra = "",
                              const std::string& light = "0,0,1.5") {
    return "<scene version=\"3.0.0\"><integrator type=\"transient_light\"><integer "
           "name=\"max_depth\" value=\"4\"/><boolean name=\"hide_emitters\" value=\"true\"/>"
           "</integrator><sensor type=\"perspective\"><float name=\"fov\" "
           "value=\"43.60281897270362\"/><transform name=\"to_world\"><lookat origin=\"0,0,5\" "
           "target=\"0,0,0\" up=\"0,1,0\"/></transform><sampler type=\"independent\"><integer "
           "name=\"sample_count\" value=\"32\"/></sampler>" +
           film +
           "</sensor><shape type=\"rectangle\"><transform name=\"to_world\"><scale "
           "value=\"10\"/></transform><bsdf type=\"diffuse\"><float name=\"reflectance\" "
           "value=\"0.6\"/></bsdf></shape><emitter type=\"point\"><point name=\"position\" "
           "value=\"" +
           light + "\"/><float name=\"intensity\" value=\"5\"/></emitter>" + extra + "</scene>";
}

std::string cube_film(int res, double start, double width, int bins, bool world_time,
                      const std::string& tfilter = "<tfilter type=\"histogram\"/>") {
    return "<film type=\"transient\"><integer name=\"width\" value=\"" + std::to_string(res) +
           "\"/><integer name=\"height\" value=\"" + std::to_string(res) +
           "\"/><float name=\"start\" value=\"" + std::to_string(start) +
           "\"/><float name=\"bin_width\" value=\"" + std::to_string(width) +
           "\"/><integer name=\"bins\" value=\"" + std::to_string(bins) +
           "\"/><boolean name=\"world_time\" value=\"" + (world_time ? "true" : "false") +
           "\"/><rfilter type=\"box\"/>" + tfilter + "</film>";
}

int bin_of(double start, double width, int bins, double t) {
    return std::clamp(int(std::floor((t - start) / width)), 0, bins - 1);
}

}  // namespace

// Every splat lands in the bins its pixel's footprint allows: light reaches plane point x at
// |x - light| and the camera |x - camera| later (camera time) or at once (world time). The
// plane is parallel to the film, so a pixel's footprint is a square; the arrival is convex in
// x, so its maximum is at a corner and its minimum is within sqrt(2) h of the smallest value on
// a grid of spacing h (the arrival changes by at most 2 per unit of x).
TEST(LightTracer, TofPlaneArrivalBinsAreExact) {
    for (const bool world : {false, true}) {
        SCOPED_TRACE(world ? "world time" : "camera time");
        const int res = 16, bins = 700;
        const double start = world ? 1.4 : 6.4, width = 0.005;
        auto scene =
            load_scene_string(pinhole_tof_plane(cube_film(res, start, width, bins, world)));
        const Cube cube = test::render_cube(*scene, 5, "light-tof");
        ASSERT_EQ(cube.T, bins);
        const Vec3 light(0, 0, 1.5f), camera(0, 0, 5);
        auto arrival = [&](double x, double y) {
            const double to_light = std::hypot(x - light.x, y - light.y, double(light.z));
            return world ? to_light : to_light + std::hypot(x, y, double(camera.z));
        };
        double total = 0;
        int failures = 0;
        for (int py = 0; py < res && failures < 10; ++py)
            for (int px = 0; px < res && failures < 10; ++px) {
                const double w = 4.0 / res, x1 = 2 - px * w, x0 = x1 - w, y1 = 2 - py * w,
                             y0 = y1 - w;  // image x runs along -x in world
                const int grid = 64;
                const double h = w / grid;
                double lo = kInfinity, hi = 0;
                for (int j = 0; j <= grid; ++j)
                    for (int i = 0; i <= grid; ++i) {
                        const double t = arrival(x0 + i * h, y0 + j * h);
                        lo = std::min(lo, t), hi = std::max(hi, t);
                    }
                const int b0 = bin_of(start, width, bins, lo - std::sqrt(2.0) * h - 1e-6);
                const int b1 = bin_of(start, width, bins, hi + 1e-6);
                double inside = 0, outside = 0;
                for (int t = 0; t < bins; ++t)
                    (t < b0 || t > b1 ? outside : inside) += cube.energy(py, px, t);
                total += inside;
                if (outside != 0) {
                    ++failures;
                    ADD_FAILURE() << "pixel " << px << "," << py << ": " << outside
                                  << " outside bins [" << b0 << ", " << b1 << "]";
                }
            }
        EXPECT_GT(total, 0.0);
    }
}

// Light through glass is late by exactly (eta - 1) d: a slab of index 1.5 and thickness 0.2
// between the light (height 2) and the plane, the camera low at the side so that it sees the
// plane under the slab without looking through it. In world time (the camera segment removed)
// the earliest light anywhere arrives along the vertical, at 2 + 0.5 * 0.2 = 2.1, and the
// bin holding 2.1 receives light; without the slab the earliest light arrives at 2.
TEST(LightTracer, GlassSlabDelayIsExact) {
    const double width = 0.01, start = 1.905;  // 2 and 2.1 lie mid-bin
    const int bins = 60;
    for (const bool slab : {false, true}) {
        SCOPED_TRACE(slab ? "through the slab" : "no slab");
        const std::string glass =
            slab ? "<shape type=\"cube\"><transform name=\"to_world\"><scale x=\"1.5\" "
                   "y=\"1.5\" z=\"0.1\"/><translate z=\"1.1\"/></transform><bsdf "
                   "type=\"dielectric\"><float name=\"int_ior\" value=\"1.5\"/><float "
                   "name=\"ext_ior\" value=\"1\"/></bsdf></shape>"
                 : "";
        std::string xml =
            pinhole_tof_plane(cube_film(32, start, width, bins, true), glass, "0,0,2");
        xml = replace_element(xml, "<transform name=\"to_world\"><lookat origin=\"0,0,5\"",
                              "</transform>",
                              "<transform name=\"to_world\"><lookat origin=\"3,0,0.5\" "
                              "target=\"0,0,0\" up=\"0,0,1\"/></transform>");
        auto scene = load_scene_string(xml);
        const Cube cube = test::render_cube(*scene, 9, "light-slab");
        const double expected = slab ? 2.1 : 2.0;
        const int first = bin_of(start, width, bins, expected);
        double early = 0, at_first = 0;
        for (int y = 0; y < cube.H; ++y)
            for (int x = 0; x < cube.W; ++x) {
                for (int t = 0; t < first; ++t) early += cube.energy(y, x, t);
                at_first += cube.energy(y, x, first);
            }
        EXPECT_EQ(early, 0.0) << "light before " << expected;
        EXPECT_GT(at_first, 0.0) << "no light in the bin of " << expected;
    }
}

// Same seed, 1 and 2 threads: the splats merge in a fixed order, so the cubes are identical.
TEST(LightTracer, BitIdenticalAcrossThreadCounts) {
    // 64x64 pixels at 8 spp: 8 chunks of light paths, 64 tiles.
    const std::vector<std::pair<std::string, std::string>> defines = {
        {"res", "64"}, {"spp", "8"}, {"bins", "64"}};
    const auto a = image_with_threads("cornell-box", "transient_light", defines, 1);
    const auto b = image_with_threads("cornell-box", "transient_light", defines, 2);
    EXPECT_EQ(a, b);
    double sum = 0;
    for (const float v : a) sum += v;
    EXPECT_GT(sum, 0.0);
}

// Splats conserve energy under the kernel filter: with the same seed the histogram and kernel
// films receive the same splats (the pilot pass has its own random streams), and when the
// window holds every arrival with room for the kernel the time integrals agree to rounding.
TEST(LightTracer, SplatsConserveEnergyUnderTheKernelFilter) {
    auto image = [&](const std::string& tfilter) {
        auto scene =
            load_scene_string(pinhole_tof_plane(cube_film(12, 0.0, 0.1, 200, false, tfilter)));
        RenderOptions opt;
        opt.seed = 11;
        render(*scene, opt);
        return scene->sensor().film().steady_image();
    };
    const auto hist = image("<tfilter type=\"histogram\"/>");
    const auto kernel =
        image("<tfilter type=\"kernel\"><integer name=\"pilot_spp\" value=\"8\"/></tfilter>");
    ASSERT_EQ(hist.size(), kernel.size());
    double h = 0, k = 0;
    for (size_t i = 0; i < hist.size(); ++i) {
        h += hist[i], k += kernel[i];
        EXPECT_NEAR(kernel[i], hist[i], 1e-4 * std::abs(hist[i]) + 1e-7) << "value " << i;
    }
    EXPECT_GT(h, 0.0);
    EXPECT_NEAR(k, h, 1e-5 * h);
}

// Bad input: a sensor light paths cannot reach, max_depth 0, and an AOV that needs camera
// samples are located errors (exit code 2 from the command line).
TEST(LightTracer, BadInputIsALocatedError) {
    const std::string ortho =
        replace_element(pinhole_tof_plane(cube_film(8, 6, 0.01, 100, false)),
                        "<sensor type=\"perspective\">", "</transform>",
                        "<sensor type=\"orthographic\"><transform name=\"to_world\"><lookat "
                        "origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/></transform>");
    {
        auto scene = load_scene_string(ortho);
        try {
            render(*scene, RenderOptions{});
            ADD_FAILURE() << "an orthographic sensor was accepted";
        } catch (const SceneError& e) {
            EXPECT_NE(std::string(e.what()).find("orthographic"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(":1:"), std::string::npos) << e.what();
        }
    }
    const std::string depth0 = replace_element(pinhole_tof_plane(cube_film(8, 6, 0.01, 100, false)),
                                               "<integer name=\"max_depth\"", "/>",
                                               "<integer name=\"max_depth\" value=\"0\"/>");
    EXPECT_NE(test::load_error(depth0).find("max_depth >= 1"), std::string::npos);
    const std::string variance =
        replace_element(pinhole_tof_plane(cube_film(8, 6, 0.01, 100, false)), "<rfilter", "/>",
                        "<string name=\"aovs\" value=\"variance\"/><rfilter type=\"box\"/>");
    auto scene = load_scene_string(variance);
    try {
        render(*scene, RenderOptions{});
        ADD_FAILURE() << "the variance AOV was accepted";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("aovs"), std::string::npos) << e.what();
    }
}
