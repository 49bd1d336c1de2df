// Real Mitsuba scene files written by others load and render unchanged, with only the
// deliberately ignored parameters reported. The files are not part of the repository: they
// are read from a compat-scenes/ folder beside it (CI has one); without it these tests skip.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "femto/log.h"
#include "femto/sensor.h"
#include "scene_util.h"

using namespace femto;

namespace {

const std::string kCompat = std::string(FEMTO_SHARED_DIR) + "/compat-scenes";

// Skips the calling test, saying what is missing, when the compat scenes are not there.
#define SKIP_WITHOUT_COMPAT_SCENES()                                                    \
    if (!std::filesystem::is_directory(kCompat))                                        \
    GTEST_SKIP() << kCompat                                                             \
                 << " not found: these tests read real Mitsuba scenes kept beside the " \
                    "repository (CI has them)"

std::vector<float> render_image(Scene& scene, uint64_t seed, uint32_t spp) {
    RenderOptions opt;
    opt.seed = seed;
    opt.spp = spp;
    render(scene, opt);
    return scene.sensor().film().steady_image();
}

}  // namespace

TEST(Compat, Mitsuba06CornellBoxMeanIsStableAcrossSeeds) {
    SKIP_WITHOUT_COMPAT_SCENES();
    const std::string path = kCompat + "/mitsuba06-cbox/mts1-cbox-rgb.xml";
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    LoadOptions opt;  // strict: every parameter of the file is accepted (focusDistance too)
    opt.defines = {{"res", "64"}};
    const int warnings_before = warning_count();
    auto a = load_scene(path, opt);
    EXPECT_EQ(warning_count() - warnings_before, 0);
    EXPECT_EQ(a->shapes().size(), 8u);
    EXPECT_EQ(a->emitters().size(), 1u);
    EXPECT_EQ(a->sensor().film().width(), 64);
    auto b = load_scene(path, opt);
    const auto ia = render_image(*a, 1, 16), ib = render_image(*b, 2, 16);
    // Mean difference of the two seeds against its standard error, estimated from 8x8-pixel
    // block means (blocks are wider than the Gaussian filter, so they are independent).
    const int W = 64, B = 8;
    std::vector<double> blocks;
    double mean_a = 0;
    for (int by = 0; by < W / B; ++by)
        for (int bx = 0; bx < W / B; ++bx) {
            double d = 0;
            for (int y = by * B; y < (by + 1) * B; ++y)
                for (int x = bx * B; x < (bx + 1) * B; ++x)
                    for (int c = 0; c < 3; ++c) {
                        const size_t i = 3 * size_t(y * W + x) + c;
                        d += double(ia[i]) - ib[i];
                        mean_a += ia[i];
                    }
            blocks.push_back(d / (B * B * 3));
        }
    mean_a /= double(W * W * 3);
    double m = 0, v = 0;
    for (double d : blocks) m += d;
    m /= double(blocks.size());
    for (double d : blocks) v += (d - m) * (d - m);
    const double se = std::sqrt(v / double(blocks.size() - 1) / double(blocks.size()));
    EXPECT_GT(mean_a, 0.05);  // a lit room, not black
    EXPECT_LT(std::abs(m), 4 * se) << "mean " << mean_a << " seed difference " << m << " se " << se;
}

TEST(Compat, VeachMisLoadsAndRenders) {
    SKIP_WITHOUT_COMPAT_SCENES();
    const std::string path = kCompat + "/veach-mis/scene.xml";
    LoadOptions opt;
    opt.lenient = true;  // strictNormals and the film's gamma are ignored
    const int warnings_before = warning_count();
    auto scene = load_scene(path, opt);
    EXPECT_EQ(warning_count() - warnings_before, 2);
    EXPECT_EQ(scene->shapes().size(), 9u);
    EXPECT_EQ(scene->emitters().size(), 3u);
    EXPECT_EQ(scene->sensor().film().width(), 320);
    EXPECT_EQ(scene->sensor().sampler().type_name(), "ldsampler");  // Mitsuba's sobol
    EXPECT_EQ(scene->sensor().film().rfilter().type_name(), "tent");
    const auto img = render_image(*scene, 1, 4);
    // maxDepth = 1 means "directly visible emitters only" (Mitsuba's definition): the image
    // holds the three sphere lights and nothing else.
    double lit = 0;
    for (float v : img) lit += v > 0;
    EXPECT_GT(lit, 0);
    EXPECT_LT(lit / double(img.size()), 0.2);
}
