// Time-window pruning (ch. 5.6.1) and its switch, the time-resolved films' `prune_paths`: a
// path that can no longer arrive within the window stops, and a connection that would arrive
// too late is not traced. Pruning only skips work whose light the film would not record, so
// turning it off must leave the cube unchanged: bit for bit where the random numbers of the
// recorded contributions do not depend on the window (surfaces: nothing is drawn differently
// before a path expires), within noise where a strategy bounds its samples by the time left
// (a line-to-point connection places its vertex on the part of the ray that still arrives).
#include <gtest/gtest.h>

#include "agreement_util.h"
#include "femto/path_clock.h"
#include "scene_util.h"

using namespace femto;

namespace {

// A point light at (0, 0, 2) over a rectangle; a transient film of window [1, 3).
std::unique_ptr<Scene> small_scene(bool prune) {
    return load_scene_string(test::scene_xml(
        "<sensor type=\"perspective\"><film type=\"transient\"><integer name=\"width\" "
        "value=\"4\"/><integer name=\"height\" value=\"4\"/><float name=\"start\" value=\"1\"/>"
        "<float name=\"bin_width\" value=\"0.5\"/><integer name=\"bins\" value=\"4\"/>"
        "<boolean name=\"prune_paths\" value=\"" +
        std::string(prune ? "true" : "false") +
        "\"/></film></sensor><shape type=\"rectangle\"/><emitter type=\"point\"><point "
        "name=\"position\" value=\"0,0,2\"/></emitter>"));
}

// The Cornell box (scenes/cornell-box) at 32x32 with `integrator`, a window [3.5, 5.5) that
// cuts most paths of up to 8 segments (they reach 30), and pruning on or off.
std::string short_window_cornell(const std::string& integrator, bool prune) {
    std::string xml = test::with_integrator("cornell-box", integrator, 8, false);
    const std::string film = "<film type=\"transient\">";
    const size_t at = xml.find(film);
    EXPECT_NE(at, std::string::npos);
    if (at == std::string::npos) return xml;
    xml.insert(at + film.size(), std::string("<boolean name=\"prune_paths\" value=\"") +
                                     (prune ? "true" : "false") + "\"/>");
    return xml;
}

}  // namespace

TEST(WindowPruning, OffTheClocksNeverCut) {
    auto pruned = small_scene(true), unpruned = small_scene(false);
    const TimeWindow &on = pruned->time_window(), &off = unpruned->time_window();
    EXPECT_TRUE(on.prune);
    EXPECT_FALSE(off.prune);
    EXPECT_TRUE(on.bounded());
    EXPECT_FALSE(off.bounded());  // paths then need a depth limit or roulette
    // The window itself stays the film's: time-sampling strategies spread vertices over it.
    EXPECT_DOUBLE_EQ(off.end, 3.0);
    EXPECT_DOUBLE_EQ(on.path_cut(), 3.0);
    EXPECT_TRUE(std::isinf(off.path_cut()));
    EXPECT_TRUE(std::isinf(off.path_cut(0.5)));
    EXPECT_DOUBLE_EQ(on.light_cut(), 3.0);
    EXPECT_TRUE(std::isinf(off.light_cut()));

    ContributionList a, b;
    PathClock camera_on(*pruned, a, Vec3(0.f)), camera_off(*unpruned, b, Vec3(0.f));
    camera_on.delay(10.0), camera_off.delay(10.0);
    EXPECT_TRUE(camera_on.expired());
    EXPECT_FALSE(camera_off.expired());
    EXPECT_TRUE(std::isinf(camera_off.remaining()));

    auto sampler = create_default_object(PluginKind::Sampler, "independent", {});
    Sampler& s = static_cast<Sampler&>(*sampler);
    s.start(1, 0, 0);
    const Emitter& light = *pruned->emitters()[0];
    LightClock light_on(*pruned, light, Vec3(0.f), s), light_off(*unpruned, light, Vec3(0.f), s);
    EXPECT_TRUE(light_on.arrives_in_time(2.5));
    EXPECT_FALSE(light_on.arrives_in_time(3.5));
    EXPECT_TRUE(light_off.arrives_in_time(3.5));
    light_on.delay(10.0), light_off.delay(10.0);
    EXPECT_TRUE(light_on.expired());
    EXPECT_FALSE(light_off.expired());
    EXPECT_FALSE(camera_on.arrives_in_time(light_on, 0.0));
    EXPECT_TRUE(camera_off.arrives_in_time(light_off, 0.0));
}

TEST(WindowPruning, OffNeedsADepthLimitOrRoulette) {
    // Without pruning nothing ends a path of max_depth -1 and no roulette: refused before the
    // render starts; with pruning the window ends those paths.
    for (bool prune : {false, true}) {
        const std::string xml = test::replace_element(
            short_window_cornell("transient_path", prune), "<integrator", "</integrator>",
            "<integrator type=\"transient_path\"><integer name=\"max_depth\" value=\"-1\"/>"
            "<integer name=\"rr_depth\" value=\"0\"/></integrator>");
        LoadOptions options;
        options.defines = {{"res", "8"}, {"spp", "1"}, {"bins", "40"}};
        auto scene = load_scene_string(xml, options, test::kScenes);
        std::string error;
        try {
            femto::testing::render_steady(*scene, 1);
        } catch (const SceneError& e) {
            error = e.what();
        }
        if (prune)
            EXPECT_EQ(error, "");
        else
            EXPECT_NE(error.find("prune_paths on"), std::string::npos) << error;
    }
}

TEST(WindowPruning, OffGivesTheSameCubeOnSurfaces) {
    // The path tracer and the light tracer, pruning on and off, the same seed: the same cube,
    // bit for bit. The window cuts most paths, so pruning is at work.
    LoadOptions options;
    options.defines = {{"res", "32"}, {"spp", "8"}, {"bins", "40"}};
    for (const std::string integrator : {"transient_path", "transient_light"}) {
        auto on = load_scene_string(short_window_cornell(integrator, true), options, test::kScenes);
        auto off =
            load_scene_string(short_window_cornell(integrator, false), options, test::kScenes);
        const femto::testing::Cube a = femto::testing::render_cube(*on, 5, "prune-on");
        const femto::testing::Cube b = femto::testing::render_cube(*off, 5, "prune-off");
        ASSERT_EQ(a.data.size(), b.data.size());
        double energy = 0;
        size_t differ = 0;
        for (size_t i = 0; i < a.data.size(); ++i) {
            energy += a.data[i];
            differ += a.data[i] != b.data[i];
        }
        EXPECT_GT(energy, 0.0) << integrator;
        EXPECT_EQ(differ, 0u) << integrator << ": values that differ out of " << a.data.size();
    }
}

TEST(WindowPruning, OffAgreesWithinNoiseInBidirectionalAndLineToPoint) {
    // BDPT draws a camera subpath and then a light subpath from one random stream: a camera
    // subpath that pruning no longer stops shifts the light subpath's numbers, so the cubes
    // differ sample by sample and must agree in expectation. So must transient_path with
    // line-to-point connections in fog, whose vertices lie on the part of a ray that still
    // arrives in time (the whole ray without pruning).
    constexpr int kRuns = 16;
    struct Case {
        std::string name, xml;
        std::vector<std::pair<std::string, std::string>> defines;
        int block, group;
    };
    // Without pruning fog-point's paths (no depth limit, no roulette) need a depth limit: 60
    // segments, more than fit in the window (12 mm of 0.244 mm mean free paths).
    std::string fog = test::shipped_scene_text("fog-point");
    const std::string integrator = "<integrator type=\"transient_path\">";
    ASSERT_NE(fog.find(integrator), std::string::npos);
    fog.insert(fog.find(integrator) + integrator.size(),
               "<integer name=\"max_depth\" value=\"60\"/>");
    const std::string film = "<film type=\"transient\">";
    auto without_pruning = [&](std::string xml) {
        xml.insert(xml.find(film) + film.size(), "<boolean name=\"prune_paths\" value=\"false\"/>");
        return xml;
    };
    ASSERT_NE(fog.find(film), std::string::npos);
    const std::vector<Case> cases = {
        {"bdpt",
         short_window_cornell("transient_bdpt", true),
         {{"res", "16"}, {"spp", "8"}, {"bins", "40"}},
         4,
         4},
        {"fog line_to_point",
         fog,
         {{"res", "16"}, {"spp", "48"}, {"connection", "line_to_point"}},
         4,
         10},
    };
    for (const Case& c : cases) {
        LoadOptions options;
        options.defines = c.defines;
        const std::string off = c.name == "bdpt" ? short_window_cornell("transient_bdpt", false)
                                                 : without_pruning(c.xml);
        const auto a = test::render_runs(c.xml, options, kRuns, 100, "prune-on");
        const auto b = test::render_runs(off, options, kRuns, 200, "prune-off");
        test::expect_agree(test::cells_of(b, c.block, c.group), test::cells_of(a, c.block, c.group),
                           kRuns, c.name);
    }
}
