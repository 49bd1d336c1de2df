// Every scene shipped in scenes/ loads and renders (at 8x8 pixels, 2 spp), and its film refuses
// no contribution (NaN, infinite, negative): a scene that stops loading after a change of the
// format or of a plugin fails here, not in a user's hands.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
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

// A render loads the plugin libraries its scene names (and the defaults of what it leaves
// out), no others (issue 12 §4): read from this process's own memory map after rendering
// scenes/cornell-box (each test runs in its own process).
namespace {
// The plugin libraries mapped into this process.
std::set<std::string> loaded_plugins() {
    std::ifstream maps("/proc/self/maps");
    std::set<std::string> loaded;
    for (std::string line; std::getline(maps, line);) {
        const size_t slash = line.rfind('/');
        if (slash == std::string::npos || line.find("/plugins/") == std::string::npos) continue;
        const std::string name = line.substr(slash + 1);
        if (name.size() > 3 && name.substr(name.size() - 3) == ".so") loaded.insert(name);
    }
    return loaded;
}
}  // namespace

TEST(ShippedScenes, ARenderLoadsOnlyThePluginsItsSceneNames) {
    if (!loaded_plugins().empty())
        GTEST_SKIP() << "an earlier test in this process loaded plugins; run this test alone "
                        "(ctest runs each test in its own process)";
    const std::filesystem::path file =
        std::filesystem::path(FEMTO_SOURCE_DIR) / "scenes" / "cornell-box" / "scene.xml";
    LoadOptions options;
    options.defines = {{"res", "4"}, {"spp", "1"}, {"bins", "4"}};
    auto scene = load_scene(file.string(), options);
    RenderOptions render_options;
    render(*scene, render_options);
    const std::set<std::string> loaded = loaded_plugins();
    // The scene's types (histogram and transient_path are its $tfilter and $integrator), and
    // the defaults of the elements it leaves out: transient_path's time-sampling strategies
    // (<distance>, <connection>, <angular>), built at load even in a scene without media, where
    // the integrator never calls them.
    const std::set<std::string> expected = {"area.so",           "box.so",
                                            "cube.so",           "diffuse.so",
                                            "ldsampler.so",      "perspective.so",
                                            "rectangle.so",      "transient.so",
                                            "histogram.so",      "transient_path.so",
                                            "mean_free_path.so", "deterministic.so",
                                            "phase.so"};
    EXPECT_EQ(loaded, expected);
}
