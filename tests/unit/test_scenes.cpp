// Every scene shipped in scenes/ loads and renders (at 8x8 pixels, 2 spp), and its film refuses
// no contribution (NaN, infinite, negative): a scene that stops loading after a change of the
// format or of a plugin fails here, not in a user's hands.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "femto/host.h"
#include "femto/sensor.h"

using namespace femto;

TEST(ShippedScenes, EveryOneLoadsAndRenders) {
    const std::filesystem::path dir = std::filesystem::path(FEMTO_SOURCE_DIR) / "scenes";
    int count = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        const auto file = entry.path() / "scene.xml";
        if (!entry.is_directory() || !std::filesystem::exists(file)) continue;
        SCOPED_TRACE(file.string());
        LoadOptions options;
        options.defines = {{"res", "8"}, {"spp", "2"}};
        auto scene = load_scene(file.string(), options);
        RenderOptions render_options;
        render_options.seed = 1;
        const RenderStats stats = render(*scene, render_options);
        EXPECT_EQ(stats.spp_done, 2u);
        double sum = 0;
        for (const float v : scene->sensor().film().steady_image()) sum += v;
        EXPECT_GT(sum, 0.0) << "no light reached the film";
        const RejectedContributions r = stats.rejected;
        EXPECT_EQ(r.total(), 0u) << "refused contributions: " << r.nan << " NaN, " << r.infinite
                                 << " infinite, " << r.negative << " negative";
        ++count;
    }
    EXPECT_GE(count, 9);
}
