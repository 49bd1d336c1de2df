// Adaptive sampling (thesis ch. 3, Fig. 3.15): a pixel whose camera ray meets a material with a
// sample share s first takes spp_p = max(1, ceil(s spp_0)) samples (Bsdf::pixel_sample_share(),
// the btf material's `adaptive_spp` table over the texel-to-pixel ratio). The renderer takes
// exactly those counts, the films normalise each pixel by its own samples (the image keeps its
// expectation), and integrators that splat keep spp everywhere.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "btf_test_util.h"
#include "femto/bsdf.h"
#include "femto/host.h"
#include "femto/scene.h"
#include "scene_util.h"

namespace {

using namespace femto;
using namespace femto::test;

std::string btf_file() { return write_btf(small_btf_a(), "adaptive", "a.dfmf"); }

std::shared_ptr<Bsdf> make_btf(const std::string& table) {
    Properties p("btf", {});
    p.set_string("filename", btf_file());
    p.set_string("adaptive_spp", table);
    return std::static_pointer_cast<Bsdf>(create_object(PluginKind::Bsdf, "btf", p));
}

/// A camera hit whose pixel spans `ratio` texels of the 8 x 4 BTF along u.
Hit hit_at_ratio(double ratio) {
    Hit hit;
    hit.dpdu = Vec3(1, 0, 0);
    hit.footprint.valid = true;
    hit.footprint.duv_dx = Vec2(float(ratio / 8), 0.f);
    return hit;
}

TEST(AdaptiveSampling, BtfShareFollowsItsTableInLog2Ratio) {
    const auto bsdf = make_btf("1:1, 4:0.5, 16:0.25");
    EXPECT_TRUE(bsdf->adapts_sampling());
    const std::pair<double, float> expected[] = {{0.25, 1.f}, {1, 1.f},    {2, 0.75f},  {4, 0.5f},
                                                 {8, 0.375f}, {16, 0.25f}, {256, 0.25f}};
    for (const auto& [ratio, share] : expected)
        EXPECT_NEAR(bsdf->pixel_sample_share(hit_at_ratio(ratio)), share, 1e-6) << ratio;
    EXPECT_EQ(bsdf->pixel_sample_share(Hit{}), 1.f);  // no footprint: the full count
    EXPECT_FALSE(make_btf("")->adapts_sampling());
}

TEST(AdaptiveSampling, BadTablesAreLocatedErrors) {
    for (const char* bad : {"4:0.5, 1:1", "1:0", "1:1.5", "abc", "1:1:2", "1", "0:1", "1:1,,"}) {
        const std::string xml = scene_xml(
            "<shape type=\"rectangle\"><bsdf type=\"btf\"><string name=\"filename\" value=\"" +
            btf_file() + "\"/><string name=\"adaptive_spp\" value=\"" + bad +
            "\"/></bsdf></shape>");
        try {
            load_scene_string(xml);
            ADD_FAILURE() << "accepted adaptive_spp \"" << bad << "\"";
        } catch (const SceneError& e) {
            EXPECT_NE(std::string(e.what()).find("adaptive_spp"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("<string>:3:"), std::string::npos) << e.what();
        }
    }
}

// A 32 x 32 orthographic view of two unit-wide rectangles side by side under a directional
// light: a BTF (uv_scale 8: 4 texels per pixel) on the left 16 columns, a diffuse one on the
// right 16. With `table` "1:1, 4:0.25" the BTF's pixels take a quarter of the samples.
std::string two_surfaces(const std::string& integrator, const std::string& table, int spp,
                         const std::string& sensor = "orthographic") {
    return "<scene version=\"3.0.0\"><integrator type=\"" + integrator +
           "\"><integer name=\"max_depth\" value=\"2\"/></integrator>"
           "<sensor type=\"" +
           sensor +
           "\"><transform name=\"to_world\"><lookat origin=\"0, 0, "
           "5\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>" +
           independent_sampler(spp) +
           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer "
           "name=\"height\" value=\"32\"/><rfilter type=\"box\"/></film></sensor>"
           "<emitter type=\"directional\"><vector name=\"direction\" x=\"0.3\" y=\"0.2\" "
           "z=\"-1\"/></emitter>"
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale x=\"0.5\"/>"
           "<translate x=\"-0.5\"/></transform><bsdf type=\"btf\"><string name=\"filename\" "
           "value=\"" +
           btf_file() +
           "\"/><float name=\"uv_scale\" value=\"8\"/><string name=\"adaptive_spp\" value=\"" +
           table +
           "\"/></bsdf></shape>"
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale x=\"0.5\"/>"
           "<translate x=\"0.5\"/></transform></shape></scene>";
}

TEST(AdaptiveSampling, PixelsTakeTheirCountsAndKeepTheirExpectation) {
    constexpr int kSpp = 16;
    const auto adaptive = load_scene_string(two_surfaces("path", "1:1, 4:0.25", kSpp));
    RenderOptions opt;
    opt.seed = 1;
    const RenderStats stats = render(*adaptive, opt);
    EXPECT_TRUE(stats.adaptive);
    // 16 columns of BTF at ceil(0.25 x 16) = 4 samples, 16 of diffuse at 16.
    EXPECT_EQ(stats.camera_samples, uint64_t(32 * 16 * 4 + 32 * 16 * kSpp));
    const std::vector<float> a = adaptive->sensor().film().steady_image();

    const auto plain = load_scene_string(two_surfaces("path", "", kSpp));
    opt.seed = 2;
    const RenderStats plain_stats = render(*plain, opt);
    EXPECT_FALSE(plain_stats.adaptive);
    EXPECT_EQ(plain_stats.camera_samples, uint64_t(32 * 32 * kSpp));
    const std::vector<float> b = plain->sensor().film().steady_image();
    // Per half, the mean difference of the two renders is zero within its standard error
    // (independent pixels): a film that divided by the base count would make the BTF half 4x
    // darker.
    for (const int half : {0, 1})
        for (int c = 0; c < 3; ++c) {
            std::vector<double> diff, level;
            for (int y = 0; y < 32; ++y)
                for (int x = 16 * half; x < 16 * half + 16; ++x) {
                    const size_t i = 3 * size_t(y * 32 + x) + size_t(c);
                    diff.push_back(double(a[i]) - b[i]);
                    level.push_back(b[i]);
                }
            const auto d = femto::testing::mean_and_error(diff);
            const double mean = femto::testing::mean_and_error(level).mean;
            ASSERT_GT(mean, 0.01);
            EXPECT_LT(std::abs(d.mean), 5 * d.standard_error + 1e-6 * mean)
                << "half " << half << ", channel " << c << ": " << d.mean << " +- "
                << d.standard_error << " against " << mean;
        }
}

TEST(AdaptiveSampling, SplattingIntegratorsKeepTheFullCount) {
    // BDPT splats its light-tracing strategy (t = 1) onto a pinhole camera's pixels.
    const auto scene =
        load_scene_string(two_surfaces("transient_bdpt", "1:1, 4:0.25", 2, "perspective"));
    RenderOptions opt;
    const RenderStats stats = render(*scene, opt);
    EXPECT_FALSE(stats.adaptive);
    EXPECT_EQ(stats.camera_samples, uint64_t(32 * 32 * 2));
}

}  // namespace
