// Energy of temporal reconstruction (issue 4: "kernel and histogram cubes of the same render
// sum to the same steady image"). Built into femto_io_tests because it reads the EXR header.
//
// The kernel filter adds no randomness: with the same seed both films receive the same
// contributions (samplers draw per pixel and sample index), and the kernel only spreads each
// one over several bins with weights that sum to its mass inside the window. So:
//  - when the window holds every arrival with room for the kernel, the cubes' sums agree per
//    pixel up to float rounding (a pixel value sums <= 16 samples x a few dozen bins in
//    float: relative error well below 1e-5, which is the tolerance, plus 1e-9 absolute);
//  - when the window cuts through the light, the kernel moves mass across its edges; the
//    film reports it as femto:window_spill (an image mean, normalised like the steady image)
//    and kernel mean + spill = histogram mean, to the same rounding.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "femto/film.h"
#include "femto/host.h"
#include "femto/image_io.h"
#include "femto/sensor.h"
#include "scene_util.h"

using namespace femto;

namespace {

// Orthographic view of a diffuse plane and a small wall, lit by a point light at height 2:
// direct light arrives from t ~ 7 on (camera at z = 5), then up to two more bounces.
std::string plane_scene(double start, double bin_width, int bins, const std::string& tfilter) {
    std::ostringstream s;
    s << "<scene version=\"3.0.0\"><integrator type=\"transient_path\"><integer name=\"max_depth\" "
         "value=\"3\"/>"
         "</integrator><sensor type=\"orthographic\"><transform name=\"to_world\">"
         "<scale x=\"3\" y=\"3\"/><lookat origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/>"
         "</transform><sampler type=\"independent\"><integer name=\"sample_count\" "
         "value=\"16\"/></sampler><film type=\"transient\"><integer name=\"width\" "
         "value=\"24\"/><integer name=\"height\" value=\"20\"/><float name=\"start\" value=\""
      << start << "\"/><float name=\"bin_width\" value=\"" << bin_width
      << "\"/><integer name=\"bins\" value=\"" << bins << "\"/>" << tfilter
      << "<rfilter type=\"box\"/></film></sensor>"
         "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2.5\"/>"
         "</transform><bsdf type=\"diffuse\"/></shape>"
         "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.5\"/>"
         "<rotate x=\"1\" angle=\"90\"/><translate x=\"1\" z=\"0.5\"/></transform>"
         "<bsdf type=\"diffuse\"/></shape>"
         "<emitter type=\"point\"><point name=\"position\" x=\"0.3\" y=\"-0.2\" z=\"2\"/>"
         "<rgb name=\"intensity\" value=\"4, 3, 2\"/></emitter></scene>";
    return s.str();
}

// The pilot in the image takes all 16 samples of the render; with 8 (pilot_spp 8), the image
// passes after it take the rest; a separate pilot's samples are not in the image.
const char* const kKernel =
    "<tfilter type=\"kernel\"><integer name=\"pilot_spp\" value=\"16\"/></tfilter>";
const char* const kKernelHalfPilot =
    "<tfilter type=\"kernel\"><integer name=\"pilot_spp\" value=\"8\"/></tfilter>";
const char* const kKernelSeparatePilot =
    "<tfilter type=\"kernel\"><integer name=\"pilot_spp\" value=\"16\"/><boolean "
    "name=\"pilot_in_image\" value=\"false\"/></tfilter>";

struct Result {
    std::vector<float> steady;
    double spill[3] = {0, 0, 0};
    std::string tfilter;
};

Result render_to_files(const std::string& xml, const std::string& name) {
    auto scene = load_scene_string(xml);
    RenderOptions ro;
    ro.seed = 11;
    ro.threads = 2;
    const RenderStats stats = render(*scene, ro);
    const Film& film = scene->sensor().film();
    const auto dir = test::temp_dir("tfilter-energy-" + name);
    const std::string base = (dir / name).string();
    film.write(base, make_render_info(*scene, ro, stats));
    const io::Cube cube = io::read_exr_cube(base + ".exr");
    Result r;
    r.steady = film.steady_image();
    r.tfilter = *cube.attribute("femto:tfilter");
    if (const std::string* spill = cube.attribute("femto:window_spill")) {
        std::istringstream in(*spill);
        in >> r.spill[0] >> r.spill[1] >> r.spill[2];
    }
    // The cube read back sums to the steady image too (what a user loads).
    for (int p = 0; p < cube.width * cube.height; ++p)
        for (int c = 0; c < 3; ++c) {
            double sum = 0;
            for (int t = 0; t < cube.bins; ++t)
                sum += cube.data[(size_t(p) * size_t(cube.bins) + size_t(t)) * 3 + size_t(c)];
            EXPECT_NEAR(sum, r.steady[size_t(p) * 3 + size_t(c)], 1e-5 * std::abs(sum) + 1e-9);
        }
    std::filesystem::remove_all(dir);
    return r;
}

double mean(const std::vector<float>& v, int c) {
    double s = 0;
    for (size_t i = size_t(c); i < v.size(); i += 3) s += v[i];
    return s / double(v.size() / 3);
}

TEST(TemporalFilterEnergy, KernelAndHistogramSumToTheSameSteadyImage) {
    // Window [0, 40): arrivals lie in ~[7, 20], far from both edges even for the widest
    // kernel the pilot may choose (1/8 of the window, 5 units).
    const Result h = render_to_files(plane_scene(0.0, 0.1, 400, ""), "hist");
    ASSERT_EQ(h.tfilter, "histogram");
    for (const char* tfilter : {kKernel, kKernelHalfPilot, kKernelSeparatePilot}) {
        SCOPED_TRACE(tfilter);
        const Result k = render_to_files(plane_scene(0.0, 0.1, 400, tfilter), "kernel");
        ASSERT_EQ(k.tfilter, "kernel");
        ASSERT_EQ(h.steady.size(), k.steady.size());
        int bad = 0;
        for (size_t i = 0; i < h.steady.size(); ++i)
            if (std::abs(h.steady[i] - k.steady[i]) >
                    1e-5 * std::max(std::abs(h.steady[i]), std::abs(k.steady[i])) + 1e-9 &&
                ++bad <= 10)
                ADD_FAILURE() << "value " << i << ": histogram " << h.steady[i] << ", kernel "
                              << k.steady[i];
        EXPECT_EQ(bad, 0);
        for (int c = 0; c < 3; ++c) {
            EXPECT_GT(mean(h.steady, c), 0.01);  // not vacuous
            EXPECT_NEAR(k.spill[c], 0.0, 1e-6 * mean(h.steady, c));
        }
    }
}

TEST(TemporalFilterEnergy, WhatTheKernelMovesOutOfTheWindowIsAccountedFor) {
    // Window [7.5, 11.5): direct light reaches a pixel at 5 + |x - light|, from 7 under the
    // light to ~8.5 in the corners, so the window's start cuts through the direct arrivals and
    // a kernel of half-width 0.3 moves energy across it both ways. The pilot's kernel is
    // checked as well (it may spill less).
    const Result h = render_to_files(plane_scene(7.5, 0.1, 40, ""), "hist-cut");
    const Result k = render_to_files(
        plane_scene(7.5, 0.1, 40,
                    "<tfilter type=\"kernel\"><float name=\"bandwidth\" value=\"0.3\"/></tfilter>"),
        "kernel-cut");
    const Result p = render_to_files(plane_scene(7.5, 0.1, 40, kKernel), "pilot-cut");
    for (int c = 0; c < 3; ++c) {
        SCOPED_TRACE(c);
        const double hm = mean(h.steady, c), km = mean(k.steady, c), pm = mean(p.steady, c);
        EXPECT_GT(std::abs(hm - km), 3e-3 * hm);  // it did spill (~0.9 %): not vacuous
        EXPECT_NEAR(km + k.spill[c], hm, 1e-5 * hm);
        EXPECT_NEAR(pm + p.spill[c], hm, 1e-5 * hm);
    }
}

}  // namespace
