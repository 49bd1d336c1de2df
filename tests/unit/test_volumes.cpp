// Volumes (`gridvolume`, `constvolume`) and the Mitsuba media syntax that uses them
// (docs/media.md, docs/compatibility.md): the grid layouts of Mitsuba 0.6 and 3, file names
// resolved by the loader next to the file that names them, Mitsuba 0.6 and 3 media scenes
// rendering as their femto-native equivalents, and bad input as located errors.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "femto/host.h"
#include "femto/medium.h"
#include "femto/random.h"
#include "femto/shape.h"
#include "femto/volume.h"
#include "scene_util.h"
#include "vol_util.h"

namespace {

namespace fs = std::filesystem;
using femto::Color;
using femto::PluginKind;
using femto::Properties;
using femto::Vec3;
using femto::test::make_grid;
using femto::test::VolFile;
using femto::test::write_bytes;
using femto::test::write_text;

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

std::shared_ptr<femto::Volume> grid(const fs::path& file,
                                    const std::function<void(Properties&)>& extra = {}) {
    Properties p("gridvolume", {"v.xml", 1, 1});
    p.set_string("filename", file.string());
    if (extra) extra(p);
    return std::static_pointer_cast<femto::Volume>(
        femto::create_object(PluginKind::Volume, "gridvolume", p));
}

// ---------------------------------------------------------------------------------------------
// Grid layouts

double value(int x, int y, int z) { return 1.0 + x + 10.0 * y + 100.0 * z; }

TEST(GridVolume, CellLatticeFillsTheUnitCube) {
    const auto dir = femto::test::temp_dir("vol-cell");
    // The file's box is ignored by default (Mitsuba 3): value i at the centre of cell i of the
    // unit cube, the edge value between the outer centres and the faces, 0 outside.
    write_bytes(dir / "g.vol", make_grid(2, 3, 4, {5, 5, 5}, {9, 9, 9}, value).bytes());
    auto v = grid(dir / "g.vol");
    EXPECT_EQ(v->channels(), 1);
    for (int z = 0; z < 4; ++z)
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 2; ++x) {
                const Vec3 centre(float((x + 0.5) / 2), float((y + 0.5) / 3), float((z + 0.5) / 4));
                EXPECT_NEAR(v->eval_1(centre), value(x, y, z), 1e-4);
            }
    EXPECT_NEAR(v->eval_1({0.5f, 0.5f / 3, 0.125f}), 0.5 * (value(0, 0, 0) + value(1, 0, 0)), 1e-4);
    EXPECT_NEAR(v->eval_1({0.01f, 0.01f, 0.01f}), value(0, 0, 0), 1e-4);  // clamped
    EXPECT_NEAR(v->eval_1({1.f, 1.f, 1.f}), value(1, 2, 3), 1e-4);
    EXPECT_EQ(v->eval_1({1.01f, 0.5f, 0.5f}), 0.0);
    EXPECT_EQ(v->eval_1({7.f, 7.f, 7.f}), 0.0);  // the file's box means nothing here
    EXPECT_FLOAT_EQ(v->max_value().r, float(value(1, 2, 3)));
    EXPECT_FLOAT_EQ(v->min_value().r, float(value(0, 0, 0)));
    EXPECT_NEAR(v->longest_chord(), std::sqrt(3.0), 1e-9);

    // to_world places the cube; nearest takes the cell's value; repeat wraps to the far side.
    auto placed = grid(dir / "g.vol", [](Properties& p) {
        p.set_transform("to_world", femto::Transform::translate({10, 0, 0}) *
                                        femto::Transform::scale({2, 3, 4}));
        p.set_string("filter_type", "nearest");
    });
    EXPECT_NEAR(placed->eval_1({10.9f, 2.9f, 3.9f}), value(0, 2, 3), 1e-4);
    EXPECT_NEAR(placed->longest_chord(), std::sqrt(4.0 + 9.0 + 16.0), 1e-6);
    auto repeat = grid(dir / "g.vol", [](Properties& p) { p.set_string("wrap_mode", "repeat"); });
    EXPECT_NEAR(repeat->eval_1({0.f, 0.5f / 3, 0.125f}), 0.5 * (value(0, 0, 0) + value(1, 0, 0)),
                1e-4);
    fs::remove_all(dir);
}

TEST(GridVolume, VertexLatticeSpansTheFilesBox) {
    const auto dir = femto::test::temp_dir("vol-vertex");
    write_bytes(dir / "g.vol", make_grid(2, 3, 4, {0, 0, 0}, {1, 2, 3}, value).bytes());
    auto v = grid(dir / "g.vol", [](Properties& p) {
        p.set_bool("use_grid_bbox", true);
        p.set_string("lattice", "vertex");
    });
    EXPECT_NEAR(v->eval_1({0, 0, 0}), value(0, 0, 0), 1e-4);  // data points on the faces
    EXPECT_NEAR(v->eval_1({1, 2, 3}), value(1, 2, 3), 1e-4);
    EXPECT_NEAR(v->eval_1({0.5f, 1, 1}), 0.5 * (value(0, 1, 1) + value(1, 1, 1)), 1e-4);
    // Mitsuba 0.6's min / max replace the file's box.
    auto moved = grid(dir / "g.vol", [](Properties& p) {
        p.set_string("lattice", "vertex");
        p.set_point("min", {10, 10, 10});
        p.set_point("max", {11, 12, 13});
    });
    EXPECT_NEAR(moved->eval_1({11, 12, 13}), value(1, 2, 3), 1e-4);
    EXPECT_EQ(moved->eval_1({0.5f, 0.5f, 0.5f}), 0.0);
    fs::remove_all(dir);
}

TEST(GridVolume, ThreeChannelsAreAColour) {
    const auto dir = femto::test::temp_dir("vol-rgb");
    VolFile f = make_grid(1, 1, 1, {0, 0, 0}, {1, 1, 1}, [](int, int, int) { return 0.2; });
    f.channels = 3;
    f.data = {0.2f, 0.4f, 0.6f};
    write_bytes(dir / "c.vol", f.bytes());
    auto v = grid(dir / "c.vol");
    EXPECT_EQ(v->channels(), 3);
    const Color c = v->eval({0.3f, 0.3f, 0.3f});
    EXPECT_FLOAT_EQ(c.r, 0.2f);
    EXPECT_FLOAT_EQ(c.g, 0.4f);
    EXPECT_FLOAT_EQ(c.b, 0.6f);
    EXPECT_FLOAT_EQ(v->max_value().b, 0.6f);
    fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Scenes

// A small foggy box: a null cube holding the medium `medium_xml` (id "smoke"), a point light
// and a diffuse floor, seen by a 16 x 16 camera.
std::string fog_scene(const std::string& medium_xml, const std::string& version = "3.0.0",
                      int spp = 8) {
    return "<scene version=\"" + version +
           "\">\n"
           "<integrator type=\"path\"><integer name=\"max_depth\" value=\"4\"/></integrator>\n"
           "<sensor type=\"perspective\"><float name=\"fov\" value=\"50\"/>"
           "<transform name=\"to_world\"><lookat origin=\"0,0.5,4\" target=\"0,0,0\" "
           "up=\"0,1,0\"/></transform>"
           "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"" +
           std::to_string(spp) +
           "\"/></sampler>"
           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/>"
           "<integer name=\"height\" value=\"16\"/><rfilter type=\"box\"/></film></sensor>\n" +
           medium_xml +
           "\n<shape type=\"cube\"><bsdf type=\"null\"/><ref name=\"interior\" id=\"smoke\"/>"
           "</shape>\n"
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"3\"/>"
           "<rotate x=\"1\" angle=\"-90\"/><translate y=\"-1.2\"/></transform>"
           "<bsdf type=\"diffuse\"/></shape>\n"
           "<emitter type=\"point\"><point name=\"position\" x=\"0.5\" y=\"2\" z=\"1.5\"/>"
           "<rgb name=\"intensity\" value=\"20\"/></emitter>\n</scene>\n";
}

// 5 points per axis over [-1, 1]^3 (spacing 0.5), zero on the box's faces.
double smoke(int x, int y, int z) {
    if (x == 0 || y == 0 || z == 0 || x == 4 || y == 4 || z == 4) return 0.0;
    return 0.5 + 0.4 * ((x * 3 + y * 5 + z * 7) % 4);
}

const femto::Medium& interior(const femto::Scene& scene) {
    const femto::Medium* m = scene.shapes()[0]->interior();
    EXPECT_TRUE(m);
    return *m;
}

/// Total image energy over `seeds` renders of `medium` (at 32 samples per pixel): its mean and
/// standard error.
femto::testing::MeanAndError energy(const std::string& medium, const std::string& version,
                                    const std::string& dir, int seeds) {
    const std::string xml = fog_scene(medium, version, 32);
    std::vector<double> totals;
    for (int s = 0; s < seeds; ++s) {
        auto scene = femto::load_scene_string(xml, {}, dir);
        double sum = 0;
        for (float v : femto::testing::render_steady(*scene, 100 + uint64_t(s))) sum += v;
        totals.push_back(sum);
    }
    return femto::testing::mean_and_error(totals);
}

void expect_same_energy(const femto::testing::MeanAndError& a,
                        const femto::testing::MeanAndError& b, const char* what) {
    const double se = std::hypot(a.standard_error, b.standard_error);
    EXPECT_GT(a.mean, 0.0) << what;
    EXPECT_LT(se, 0.05 * a.mean) << what;  // precise enough to mean something
    EXPECT_LT(std::abs(a.mean - b.mean), 4 * se) << what << ": " << a.mean << " vs " << b.mean;
}

const char* kNativeMedium =
    "<medium type=\"heterogeneous\" id=\"smoke\"><string name=\"density\" value=\"smoke.vol\"/>"
    "<rgb name=\"albedo\" value=\"0.8\"/><float name=\"scale\" value=\"2\"/>"
    "<phase type=\"hg\"><float name=\"g\" value=\"0.5\"/></phase></medium>";

TEST(MitsubaMedia, Mitsuba06HeterogeneousRendersAsTheNativeForm) {
    const auto dir = femto::test::temp_dir("vol-mts06");
    write_bytes(dir / "smoke.vol", make_grid(5, 5, 5, {-1, -1, -1}, {1, 1, 1}, smoke).bytes());
    // As Mitsuba 0.6 writes it: nested gridvolume and constvolume, camelCase names.
    const std::string mts06 =
        "<medium type=\"heterogeneous\" id=\"smoke\">"
        "<volume name=\"density\" type=\"gridvolume\"><string name=\"filename\" "
        "value=\"smoke.vol\"/><boolean name=\"sendData\" value=\"false\"/></volume>"
        "<volume name=\"albedo\" type=\"constvolume\"><spectrum name=\"value\" value=\"0.8\"/>"
        "</volume><float name=\"scale\" value=\"2\"/>"
        "<string name=\"method\" value=\"woodcock\"/>"
        "<phase type=\"hg\"><float name=\"g\" value=\"0.5\"/></phase></medium>";
    auto native = femto::load_scene_string(fog_scene(kNativeMedium), {}, dir.string());
    auto old = femto::load_scene_string(fog_scene(mts06, "0.6.0"), {}, dir.string());
    EXPECT_FLOAT_EQ(interior(*old).majorant(), interior(*native).majorant());
    femto::testing::expect_same_image(femto::testing::render_steady(*native, 7),
                                      femto::testing::render_steady(*old, 7), "native",
                                      "Mitsuba 0.6");
    fs::remove_all(dir);
}

TEST(MitsubaMedia, Mitsuba3HeterogeneousRendersAsTheNativeForm) {
    const auto dir = femto::test::temp_dir("vol-mts3");
    const VolFile data = make_grid(5, 5, 5, {-1, -1, -1}, {1, 1, 1}, smoke);
    write_bytes(dir / "smoke.vol", data.bytes());
    write_bytes(dir / "smoke3.vol", data.bytes());
    // Mitsuba 3 centres the 5 values per axis in 5 cells of the unit cube: placing the cube on
    // [-1.25, 1.25]^3 puts them where 0.6's layout puts them on [-1, 1]^3 (and the edge cells
    // clamp to the faces' zeros), so the medium is the same.
    const std::string mts3 =
        "<medium type=\"heterogeneous\" id=\"smoke\">"
        "<volume name=\"sigma_t\" type=\"gridvolume\"><string name=\"filename\" "
        "value=\"smoke3.vol\"/><string name=\"filter_type\" value=\"trilinear\"/>"
        "<transform name=\"to_world\"><scale value=\"2.5\"/><translate value=\"-1.25\"/>"
        "</transform></volume>"
        "<rgb name=\"albedo\" value=\"0.8\"/><float name=\"scale\" value=\"2\"/>"
        "<boolean name=\"sample_emitters\" value=\"true\"/>"
        "<phase type=\"hg\"><float name=\"g\" value=\"0.5\"/></phase></medium>";
    auto native = femto::load_scene_string(fog_scene(kNativeMedium), {}, dir.string());
    auto mi3 = femto::load_scene_string(fog_scene(mts3), {}, dir.string());
    const femto::Medium &a = interior(*native), &b = interior(*mi3);
    EXPECT_FLOAT_EQ(a.majorant(), b.majorant());
    femto::Pcg32 rng(3, 4);
    for (int i = 0; i < 500; ++i) {
        const Vec3 p(float(2.6 * rng.next_double() - 1.3), float(2.6 * rng.next_double() - 1.3),
                     float(2.6 * rng.next_double() - 1.3));
        EXPECT_NEAR(a.sigma_t(p).r, b.sigma_t(p).r, 1e-4) << p.x << " " << p.y << " " << p.z;
        EXPECT_NEAR(a.sigma_s(p).g, b.sigma_s(p).g, 1e-4);
    }
    expect_same_energy(energy(kNativeMedium, "3.0.0", dir.string(), 10),
                       energy(mts3, "3.0.0", dir.string(), 10), "Mitsuba 3 grid");
    fs::remove_all(dir);
}

TEST(MitsubaMedia, ConstantDensityEqualsTheHomogeneousMedium) {
    const auto dir = femto::test::temp_dir("vol-const");
    const std::string constant =
        "<medium type=\"heterogeneous\" id=\"smoke\">"
        "<volume name=\"density\" type=\"constvolume\"><float name=\"value\" value=\"0.7\"/>"
        "</volume><rgb name=\"albedo\" value=\"0.8\"/></medium>";
    const std::string homogeneous =
        "<medium type=\"homogeneous\" id=\"smoke\"><float name=\"sigma_t\" value=\"0.7\"/>"
        "<rgb name=\"albedo\" value=\"0.8\"/></medium>";
    auto a = femto::load_scene_string(fog_scene(constant, "0.6.0"), {}, dir.string());
    auto b = femto::load_scene_string(fog_scene(homogeneous), {}, dir.string());
    const Vec3 p(0.3f, -0.2f, 0.1f);
    EXPECT_FLOAT_EQ(interior(*a).sigma_t(p).r, interior(*b).sigma_t(p).r);
    EXPECT_FLOAT_EQ(interior(*a).sigma_s(p).b, interior(*b).sigma_s(p).b);
    expect_same_energy(energy(constant, "0.6.0", dir.string(), 10),
                       energy(homogeneous, "3.0.0", dir.string(), 10), "constvolume");
    fs::remove_all(dir);
}

TEST(MitsubaMedia, HomogeneousTakesNestedConstantVolumes) {
    const auto dir = femto::test::temp_dir("vol-homog");
    const std::string plain =
        "<medium type=\"homogeneous\" id=\"smoke\"><float name=\"sigma_t\" value=\"0.7\"/>"
        "<rgb name=\"albedo\" value=\"0.9, 0.8, 0.7\"/></medium>";
    const std::string nested =
        "<medium type=\"homogeneous\" id=\"smoke\">"
        "<volume name=\"sigma_t\" type=\"constvolume\"><float name=\"value\" value=\"0.7\"/>"
        "</volume><volume name=\"albedo\" type=\"constvolume\">"
        "<rgb name=\"value\" value=\"0.9, 0.8, 0.7\"/></volume></medium>";
    auto a = femto::load_scene_string(fog_scene(plain), {}, dir.string());
    auto b = femto::load_scene_string(fog_scene(nested), {}, dir.string());
    femto::testing::expect_same_image(femto::testing::render_steady(*a, 3),
                                      femto::testing::render_steady(*b, 3), "plain", "nested");
    fs::remove_all(dir);
}

// Every "filename" parameter is resolved next to the file that names it, also in an
// <include>d file in another folder; one found nowhere is an error at its element.
TEST(VolumeFiles, NamesResolveNextToTheFileThatNamesThem) {
    const auto dir = femto::test::temp_dir("vol-names");
    fs::create_directories(dir / "media" / "grids");
    fs::create_directories(dir / "elsewhere");
    write_bytes(
        dir / "media" / "grids" / "g.vol",
        make_grid(2, 2, 2, {-1, -1, -1}, {1, 1, 1}, [](int, int, int) { return 0.5; }).bytes());
    write_text(dir / "media" / "smoke.xml",
               "<scene version=\"3.0.0\">\n<medium type=\"heterogeneous\" id=\"smoke\">\n"
               "  <volume name=\"sigma_t\" type=\"gridvolume\">\n"
               "    <string name=\"filename\" value=\"grids/g.vol\"/>\n"
               "    <boolean name=\"use_grid_bbox\" value=\"true\"/></volume>\n"
               "</medium>\n<medium type=\"heterogeneous\" id=\"short\">\n"
               "  <string name=\"density\" value=\"grids/g.vol\"/></medium>\n</scene>\n");
    const std::string scene = fog_scene("<include filename=\"media/smoke.xml\"/>");
    write_text(dir / "scene.xml", scene);
    const auto cwd = fs::current_path();
    fs::current_path(dir / "elsewhere");  // not the scene's folder
    std::unique_ptr<femto::Scene> s;
    EXPECT_NO_THROW(s = femto::load_scene((dir / "scene.xml").string()));
    if (s) {
        EXPECT_FLOAT_EQ(interior(*s).sigma_t({0, 0, 0}).r, 0.5f);
    }

    std::string bad = scene;
    write_text(dir / "media" / "smoke.xml",
               "<scene version=\"3.0.0\">\n<medium type=\"heterogeneous\" id=\"smoke\">\n"
               "  <volume name=\"sigma_t\" type=\"gridvolume\">\n"
               "    <string name=\"filename\" value=\"g.vol\"/></volume>\n</medium>\n</scene>\n");
    try {
        femto::load_scene((dir / "scene.xml").string());
        ADD_FAILURE() << "a missing grid file was accepted";
    } catch (const femto::SceneError& e) {
        const std::string what = e.what();
        EXPECT_TRUE(contains(what, "smoke.xml:4:5")) << what;
        EXPECT_TRUE(contains(what, "file \"g.vol\" not found")) << what;
        EXPECT_TRUE(contains(what, (dir / "media").string())) << what;  // the folders searched
    }
    fs::current_path(cwd);
    fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Bad input

TEST(VolumeFiles, BadVolumesAreLocatedErrors) {
    const auto dir = femto::test::temp_dir("vol-bad");
    write_bytes(dir / "g.vol", make_grid(2, 2, 2, {0, 0, 0}, {1, 1, 1}, [](int, int, int) {
                                   return 1.0;
                               }).bytes());
    VolFile rgb = make_grid(2, 2, 2, {0, 0, 0}, {1, 1, 1}, [](int, int, int) { return 0.5; });
    rgb.channels = 3;
    rgb.data.resize(24, 0.5f);
    write_bytes(dir / "rgb.vol", rgb.bytes());
    VolFile bright = rgb;
    bright.data[4] = 1.5f;
    write_bytes(dir / "bright.vol", bright.bytes());
    auto medium = [](const std::string& inside, const std::string& type = "heterogeneous") {
        return "<medium type=\"" + type + "\" id=\"smoke\">\n" + inside + "</medium>";
    };
    struct Case {
        std::string medium, expect;
    };
    const Case cases[] = {
        {medium("<volume name=\"density\" type=\"gridvolum\"/>"),
         "5:1: unknown <volume> plugin \"gridvolum\" (did you mean \"gridvolume\"?)"},
        {medium("<volume name=\"density\" type=\"gridvolume\"/>"),
         "5:1: \"gridvolume\": required parameter \"filename\""},
        {medium("<volume name=\"density\" type=\"gridvolume\"><string name=\"filename\" "
                "value=\"nothere.vol\"/></volume>"),
         "5:42: file \"nothere.vol\" not found"},
        {medium("<volume name=\"density\" type=\"gridvolume\"><string name=\"filename\" "
                "value=\"rgb.vol\"/></volume>"),
         "\"density\" has 3 channels"},
        {medium("<rgb name=\"sigma_t\" value=\"1, 2, 3\"/>"), "\"sigma_t\" has 3 channels"},
        {medium("<volume name=\"density\" type=\"constvolume\"><float name=\"value\" "
                "value=\"-1\"/></volume>"),
         "5:43: \"constvolume\": a constvolume's value must be >= 0"},
        {medium("<volume name=\"albedo\" type=\"gridvolume\"><string name=\"filename\" "
                "value=\"bright.vol\"/></volume>"),
         "albedo (the single-scattering albedo) must lie in [0, 1]"},
        {medium("<volume name=\"sigma_t\" type=\"gridvolume\"><string name=\"filename\" "
                "value=\"g.vol\"/><string name=\"wrap_mode\" value=\"wrap\"/></volume>"),
         "unknown wrap_mode \"wrap\"; valid: clamp, repeat, mirror"},
        {medium("<volume name=\"sigma_t\" type=\"gridvolume\"><string name=\"filename\" "
                "value=\"g.vol\"/></volume><transform name=\"to_world\"><scale value=\"2\"/>"
                "</transform>"),
         "a nested <volume> takes its own to_world"},
        {medium("<string name=\"density\" value=\"g.vol\"/><float name=\"sigma_t\" "
                "value=\"1\"/>"),
         "not both"},
        {medium("<texture name=\"density\" type=\"checkerboard\"/>"),
         "parameter \"density\" of <medium type=\"heterogeneous\"> takes filename|volume"},
        {medium("<volume name=\"sigma_t\" type=\"gridvolume\"><string name=\"filename\" "
                "value=\"g.vol\"/></volume>",
                "homogeneous"),
         "a homogeneous medium takes a constant sigma_t, not a <volume type=\"gridvolume\">"},
        {medium("<volume name=\"albedo\" type=\"constvolume\"><float name=\"value\" "
                "value=\"2\"/></volume>",
                "homogeneous"),
         "albedo must lie in [0, 1]"},
    };
    for (const Case& c : cases) {
        const std::string what = femto::test::load_error(fog_scene(c.medium), {}, dir.string());
        EXPECT_TRUE(contains(what, c.expect)) << "expected \"" << c.expect << "\" in: " << what;
        EXPECT_TRUE(contains(what, "<string>:")) << what;  // located in the scene
    }
    fs::remove_all(dir);
}

}  // namespace
