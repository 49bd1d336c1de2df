// transient_bdpt's strategy images (issue 11, "strategy_images"): one image per strategy (s, t)
// of its MIS-weighted contributions. They sum to the film's image (box filter, a steady film),
// every strategy that can carry light in the Cornell box appears, and the option needs a finite
// max_depth.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "agreement_util.h"
#include "femto/host.h"
#include "femto/image_io.h"
#include "femto/integrator.h"
#include "femto/sensor.h"

using namespace femto;
using namespace femto::test;

namespace {

// The Cornell box with strategy images; `steady`: into a 16x16 hdrfilm with a box filter.
std::string cornell_with_images(int max_depth, bool steady = true) {
    std::string xml = shipped_scene_text("cornell-box");
    xml = replace_element(xml, "<integrator", "</integrator>",
                          "<integrator type=\"transient_bdpt\"><integer name=\"max_depth\" "
                          "value=\"" +
                              std::to_string(max_depth) +
                              "\"/><boolean name=\"strategy_images\" value=\"true\"/>"
                              "</integrator>");
    if (!steady) return xml;
    return replace_element(xml, "<film type=\"transient\">", "</film>",
                           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer "
                           "name=\"height\" value=\"16\"/><rfilter type=\"box\"/></film>");
}

}  // namespace

TEST(BdptStrategyImages, SumToTheFilmImage) {
    auto scene = load_scene_string(cornell_with_images(3), {}, kScenes);
    RenderOptions options;
    options.seed = 5;
    options.spp = 8;
    const RenderStats stats = render(*scene, options);
    const RenderInfo info = make_render_info(*scene, options, stats);
    const auto dir = temp_dir("bdpt-images");
    const std::string base = (dir / "cb").string();
    scene->sensor().film().write(base, info);
    const std::vector<std::string> files = scene->integrator().write(base, info);
    // Paths of 1 to 3 segments: (0,2) (1,1); (0,3) (1,2) (2,1); (0,4) (1,3) (2,2) (3,1).
    EXPECT_EQ(files.size(), 9u);
    const std::vector<float> film = scene->sensor().film().steady_image();
    std::vector<double> sum(film.size(), 0.0);
    for (const std::string& file : files) {
        int w = 0, h = 0;
        const std::vector<float> rgb = io::read_image_rgb(file, w, h);
        ASSERT_EQ(w, 16);
        ASSERT_EQ(h, 16);
        for (size_t i = 0; i < rgb.size(); ++i) sum[i] += rgb[i];
    }
    double total = 0;
    for (size_t i = 0; i < film.size(); ++i) {
        total += film[i];
        // The film sums in double per tile, the images in double per strategy: rounding only.
        EXPECT_NEAR(sum[i], film[i], 1e-4 * std::abs(film[i]) + 1e-6) << "value " << i;
    }
    EXPECT_GT(total, 0.0);
    std::filesystem::remove_all(dir);
}

TEST(BdptStrategyImages, NeedAFiniteMaxDepth) {
    // A transient film: with a steady one, max_depth -1 is refused before (nothing ends paths).
    auto scene = load_scene_string(cornell_with_images(-1, false), {}, kScenes);
    try {
        render(*scene, RenderOptions{});
        ADD_FAILURE() << "strategy_images with max_depth -1 was accepted";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("strategy_images needs a finite max_depth"),
                  std::string::npos)
            << e.what();
    }
}
