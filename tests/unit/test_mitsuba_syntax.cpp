// Mitsuba XML syntax that real scene files use (docs/compatibility.md, "XML syntax"): each
// feature renders the same image as a femto-native equivalent (same seed), and its errors are
// located.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "femto/integrator.h"
#include "femto/log.h"
#include "femto/sensor.h"
#include "scene_util.h"

using namespace femto;
using femto::test::load_error;
using femto::test::write_text;
using femto::testing::expect_same_image;
using femto::testing::render_steady;

namespace fs = std::filesystem;

namespace {

// A 16x16 camera looking down -z at the origin from z = 4; `film_extra` and `sensor_extra` go
// into the film and the sensor.
std::string sensor_xml(const std::string& sensor_extra = "", const std::string& film_extra = "",
                       const std::string& lookat = "lookat") {
    return "<sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/>" + sensor_extra +
           "<transform name=\"to_world\"><" + lookat +
           " origin=\"0,0,4\" target=\"0,0,0\" up=\"0,1,0\"/></transform>"
           "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"4\"/></sampler>"
           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/>"
           "<integer name=\"height\" value=\"16\"/><rfilter type=\"box\"/>" +
           film_extra + "</film></sensor>\n";
}

const std::string kLight =
    "<emitter type=\"point\"><point name=\"position\" x=\"0.3\" y=\"0.2\" z=\"2\"/>"
    "<rgb name=\"intensity\" value=\"6\"/></emitter>\n";
const std::string kRedBsdf =
    "<bsdf type=\"diffuse\" id=\"red\"><rgb name=\"reflectance\" value=\"0.8,0.2,0.1\"/></bsdf>\n";
const std::string kShapeRefRed = "<shape type=\"rectangle\"><ref id=\"red\"/></shape>\n";

std::string scene(const std::string& body, const std::string& version = "3.0.0") {
    return "<scene version=\"" + version + "\">\n" + body + "</scene>\n";
}

// The default scene's lit red rectangle, written femto's way.
std::string native_scene() { return scene(sensor_xml() + kRedBsdf + kShapeRefRed + kLight); }

std::vector<float> render_string(const std::string& xml, const LoadOptions& opt = {},
                                 const std::string& base_dir = ".") {
    auto s = load_scene_string(xml, opt, base_dir);
    return render_steady(*s, 17);
}

std::vector<float> render_file(const fs::path& path, const LoadOptions& opt = {}) {
    auto s = load_scene(path.string(), opt);
    return render_steady(*s, 17);
}

std::string load_file_error(const fs::path& path, const LoadOptions& opt = {}) {
    try {
        load_scene(path.string(), opt);
    } catch (const SceneError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected a SceneError for " << path;
    return {};
}

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

// A unit square in the z = 0 plane facing +z (the rectangle scaled by 1/2), as an OBJ file.
const char* kQuadObj = "v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\nf 1 2 3\nf 1 3 4\n";

}  // namespace

// 9: in a 0.x file the camelCase upgrade renames parameters, not the <default>s that
// $references and -D name.
TEST(MitsubaSyntax, DefaultsKeepTheirNamesInOldFiles) {
    const std::string old = scene(
        "<default name=\"maxDepth\" value=\"1\"/>"
        "<integrator type=\"path\"><integer name=\"maxDepth\" "
        "value=\"$maxDepth\"/></integrator>" +
            sensor_xml() + kRedBsdf + kShapeRefRed + kLight,
        "0.6.0");
    // maxDepth 1 sees emitters only: the point light is invisible, the image black.
    for (float v : render_string(old)) ASSERT_EQ(v, 0.f);
    LoadOptions opt;
    opt.defines = {{"maxDepth", "2"}};
    const std::string native =
        scene("<integrator type=\"path\"><integer name=\"max_depth\" value=\"2\"/></integrator>" +
              sensor_xml() + kRedBsdf + kShapeRefRed + kLight);
    expect_same_image(render_string(old, opt), render_string(native), "0.6 -D maxDepth=2",
                      "native max_depth 2");
}

// 2: <lookAt> is Mitsuba 0.4/0.5's spelling of <lookat> (upgraded in 0.x files only).
TEST(MitsubaSyntax, CamelCaseLookAtInOldFiles) {
    const std::string body = sensor_xml("", "", "lookAt") + kRedBsdf + kShapeRefRed + kLight;
    expect_same_image(render_string(scene(body, "0.5.0")), render_string(native_scene()),
                      "<lookAt> (0.5)", "<lookat>");
    const std::string msg = load_error(scene(body, "3.0.0"));
    EXPECT_TRUE(contains(msg, "<string>:2:")) << msg;
    EXPECT_TRUE(contains(msg, "unknown transform operation <lookAt>")) << msg;
}

// 1: <path value="dir"/> adds a folder where the files named in the scene are looked up.
TEST(MitsubaSyntax, PathAddsASearchFolder) {
    const auto dir = femto::testing::temp_dir("mitsuba-path");
    fs::create_directories(dir / "assets");
    write_text(dir / "assets" / "quad.obj", kQuadObj);
    write_text(dir / "assets" / "red.xml", scene(kRedBsdf));
    const std::string shape_rest = "<ref id=\"red\"/></shape>\n";
    write_text(dir / "native.xml",
               scene(sensor_xml() + "<include filename=\"assets/red.xml\"/>" + kLight +
                     "<shape type=\"obj\"><string name=\"filename\" value=\"assets/quad.obj\"/>" +
                     shape_rest));
    write_text(dir / "path.xml",
               scene("<path value=\"assets\"/>" + sensor_xml() + "<include filename=\"red.xml\"/>" +
                     kLight + "<shape type=\"obj\"><string name=\"filename\" value=\"quad.obj\"/>" +
                     shape_rest));
    const auto native = render_file(dir / "native.xml");
    expect_same_image(render_file(dir / "path.xml"), native, "<path>", "explicit folders");

    // Meshes are read once the whole file is, so a <path> after the shape counts (as in
    // Mitsuba 3); an <include> is read where it stands, so only earlier <path>s count.
    write_text(dir / "late.xml",
               scene(sensor_xml() + "<include filename=\"assets/red.xml\"/>" + kLight +
                     "<shape type=\"obj\"><string name=\"filename\" value=\"quad.obj\"/>" +
                     shape_rest + "<path value=\"assets\"/>"));
    expect_same_image(render_file(dir / "late.xml"), native, "<path> after the mesh",
                      "explicit folders");
    write_text(dir / "late-include.xml",
               scene(sensor_xml() + "\n<include filename=\"red.xml\"/>\n<path value=\"assets\"/>" +
                     kLight + kShapeRefRed));
    std::string msg = load_file_error(dir / "late-include.xml");
    EXPECT_TRUE(contains(msg, "late-include.xml:4:1:")) << msg;
    EXPECT_TRUE(contains(msg, "included file \"red.xml\" not found (searched: " + dir.string()))
        << msg;

    // The latest <path> is searched first.
    fs::create_directories(dir / "blue");
    write_text(dir / "blue" / "red.xml",
               scene("<bsdf type=\"diffuse\" id=\"red\"><rgb name=\"reflectance\" "
                     "value=\"0.1,0.2,0.8\"/></bsdf>"));
    write_text(dir / "two.xml",
               scene("<path value=\"assets\"/><path value=\"blue\"/>" + sensor_xml() +
                     "<include filename=\"red.xml\"/>" + kLight + kShapeRefRed));
    write_text(
        dir / "blue-native.xml",
        scene(sensor_xml() + "<include filename=\"blue/red.xml\"/>" + kLight + kShapeRefRed));
    expect_same_image(render_file(dir / "two.xml"), render_file(dir / "blue-native.xml"),
                      "two <path>s", "the latest folder");

    // A file found nowhere names the folders searched; a missing folder is located.
    write_text(dir / "missing.xml",
               scene("<path value=\"assets\"/>" + sensor_xml() + kLight +
                     "<shape type=\"obj\">\n<string name=\"filename\" value=\"gone.obj\"/>"
                     "</shape>\n"));
    msg = load_file_error(dir / "missing.xml");
    EXPECT_TRUE(contains(msg, "missing.xml:5:1: file \"gone.obj\" not found (searched: " +
                                  (dir / "assets").string() + ", " + dir.string() + ")"))
        << msg;
    write_text(dir / "nofolder.xml", scene("\n<path value=\"nowhere\"/>" + sensor_xml() + kRedBsdf +
                                           kShapeRefRed + kLight));
    msg = load_file_error(dir / "nofolder.xml");
    EXPECT_TRUE(contains(msg, "nofolder.xml:3:1: <path>: folder \"nowhere\" not found")) << msg;
    write_text(dir / "file.xml", scene("<path value=\"assets/quad.obj\"/>"));
    EXPECT_TRUE(contains(load_file_error(dir / "file.xml"), "is not a folder"));
    msg = load_error(scene("<shape type=\"rectangle\">\n<path value=\".\"/></shape>"));
    EXPECT_TRUE(contains(msg, "<string>:3:1: <path> can only be a child of <scene>")) << msg;
    fs::remove_all(dir);
}

// Spectrum files are input files too: found through the <path> folders, wherever the <path>
// stands, or a located error that lists the folders searched.
TEST(MitsubaSyntax, PathFindsSpectrumFiles) {
    const auto dir = femto::testing::temp_dir("mitsuba-path-spd");
    fs::create_directories(dir / "assets");
    write_text(dir / "assets" / "red.spd",
               "# a red reflectance\n400 0.1\n550 0.2\n600 0.8\n700 0.9\n");
    const auto with = [&](const std::string& path, const std::string& file) {
        return scene(path + sensor_xml() + kLight +
                     "<shape type=\"rectangle\"><bsdf type=\"diffuse\">\n<spectrum "
                     "name=\"reflectance\" filename=\"" +
                     file + "\"/></bsdf></shape>\n");
    };
    write_text(dir / "native.xml", with("", "assets/red.spd"));
    write_text(dir / "path.xml", with("<path value=\"assets\"/>", "red.spd"));
    expect_same_image(render_file(dir / "path.xml"), render_file(dir / "native.xml"),
                      "<path> spectrum", "explicit folder");
    write_text(dir / "missing.xml", with("<path value=\"assets\"/>", "blue.spd"));
    const std::string msg = load_file_error(dir / "missing.xml");
    EXPECT_TRUE(contains(msg, "missing.xml:5:1: spectrum file \"blue.spd\" not found (searched: " +
                                  (dir / "assets").string() + ", " + dir.string() + ")"))
        << msg;
    fs::remove_all(dir);
}

// 5: $parameters in an <include>'s file name, from -D or an earlier <default>.
TEST(MitsubaSyntax, ParametersInIncludeFileNames) {
    const auto dir = femto::testing::temp_dir("mitsuba-include-param");
    fs::create_directories(dir / "parts");
    fs::create_directories(dir / "other");
    write_text(dir / "parts" / "red.xml", scene(kRedBsdf));
    write_text(dir / "other" / "red.xml",
               scene("<bsdf type=\"diffuse\" id=\"red\"><rgb name=\"reflectance\" "
                     "value=\"0.1,0.9,0.1\"/></bsdf>"));
    write_text(dir / "param.xml",
               scene("<default name=\"dir\" value=\"parts\"/>" + sensor_xml() +
                     "<include filename=\"$dir/red.xml\"/>" + kLight + kShapeRefRed));
    expect_same_image(render_file(dir / "param.xml"), render_string(native_scene()), "$dir/red.xml",
                      "native");
    LoadOptions opt;
    opt.defines = {{"dir", "other"}};
    write_text(
        dir / "other-native.xml",
        scene(sensor_xml() + "<include filename=\"other/red.xml\"/>" + kLight + kShapeRefRed));
    expect_same_image(render_file(dir / "param.xml", opt), render_file(dir / "other-native.xml"),
                      "-D dir=other", "other/red.xml");
    write_text(dir / "undefined.xml",
               scene(sensor_xml() + "\n<include filename=\"$nowhere/red.xml\"/>" + kShapeRefRed));
    const std::string msg = load_file_error(dir / "undefined.xml");
    EXPECT_TRUE(contains(msg, "undefined.xml:4:1: parameter $nowhere is not defined")) << msg;
    EXPECT_TRUE(contains(msg, "before this <include>")) << msg;
    fs::remove_all(dir);
}

// 3: a <ref> may name an object written after it; undefined ids and cycles are located errors.
TEST(MitsubaSyntax, ForwardReferences) {
    expect_same_image(render_string(scene(sensor_xml() + kShapeRefRed + kLight + kRedBsdf)),
                      render_string(native_scene()), "forward <ref>", "object first");
    // Through an alias written later, and to an object nested in a later one.
    expect_same_image(
        render_string(scene(sensor_xml() + "<shape type=\"rectangle\"><ref id=\"b\"/></shape>" +
                            kLight + "<bsdf type=\"twosided\" id=\"outer\">" + kRedBsdf +
                            "</bsdf><alias id=\"red\" as=\"b\"/>")),
        render_string(native_scene()), "forward alias of a nested object", "object first");

    std::string msg = load_error(scene(sensor_xml() +
                                       "<shape type=\"rectangle\">\n<ref id=\"rd\"/>"
                                       "</shape>" +
                                       kRedBsdf + kLight));
    EXPECT_TRUE(contains(msg,
                         "<string>:4:1: no object with id \"rd\" is defined in the scene "
                         "(did you mean \"red\"?)"))
        << msg;
    msg = load_error(scene(sensor_xml() + kShapeRefRed +
                           "<bsdf type=\"twosided\" id=\"red\"><ref id=\"b\"/></bsdf>\n"
                           "<bsdf type=\"twosided\" id=\"b\">\n<ref id=\"red\"/></bsdf>"));
    EXPECT_TRUE(contains(msg,
                         "<string>:6:1: reference cycle: \"red\" (<string>:4:1) -> \"b\" "
                         "(<string>:5:1) -> \"red\""))
        << msg;
    msg = load_error(scene(sensor_xml() +
                           "<bsdf type=\"twosided\" id=\"me\">\n<ref id=\"me\"/>"
                           "</bsdf>" +
                           kLight));
    EXPECT_TRUE(contains(msg, "<string>:4:1: reference cycle: \"me\" (<string>:3:1) -> \"me\""))
        << msg;

    // A long chain of forward references is refused, not a stack overflow.
    std::string chain;
    const int n = 3000;
    for (int i = 0; i < n; ++i)
        chain += "<bsdf type=\"twosided\" id=\"b" + std::to_string(i) + "\"><ref id=\"b" +
                 std::to_string(i + 1) + "\"/></bsdf>\n";
    chain += "<bsdf type=\"diffuse\" id=\"b" + std::to_string(n) + "\"/>\n";
    msg = load_error(scene(sensor_xml() + chain + kLight));
    EXPECT_TRUE(contains(msg, "nest more than 1000 levels deep")) << msg;
    EXPECT_TRUE(contains(msg, "<string>:")) << msg;
}

// 4: name= on objects: the slot in the scene (accepted, unique) or the parameter it binds to.
TEST(MitsubaSyntax, NamesOnObjects) {
    const std::string named_bsdf =
        "<bsdf type=\"diffuse\" id=\"red\" name=\"red\"><rgb name=\"reflectance\" "
        "value=\"0.8,0.2,0.1\"/></bsdf>\n";
    const std::string named_sensor =
        "<sensor type=\"perspective\" name=\"sensor\"><float name=\"fov\" value=\"60\"/>"
        "<transform name=\"to_world\"><lookat origin=\"0,0,4\" target=\"0,0,0\" "
        "up=\"0,1,0\"/></transform><sampler type=\"independent\" name=\"sampler\"><integer "
        "name=\"sample_count\" value=\"4\"/></sampler><film type=\"hdrfilm\" name=\"film\">"
        "<integer name=\"width\" value=\"16\"/><integer name=\"height\" value=\"16\"/><rfilter "
        "type=\"box\" name=\"rfilter\"/></film></sensor>\n";
    expect_same_image(render_string(scene(named_sensor + named_bsdf + kShapeRefRed + kLight)),
                      render_string(native_scene()), "named objects", "unnamed");

    std::string msg =
        load_error(scene(sensor_xml() + named_bsdf + "\n<bsdf type=\"diffuse\" name=\"red\"/>" +
                         kShapeRefRed + kLight));
    EXPECT_TRUE(contains(msg,
                         "<string>:5:1: name \"red\" is given to two objects of the scene "
                         "(first at <string>:3:1)"))
        << msg;
    // A nested name is the parameter the object binds to: it must take that kind.
    msg =
        load_error(scene("<sensor type=\"perspective\">\n<film type=\"hdrfilm\" "
                         "name=\"sampler\"/></sensor>" +
                         kLight));
    EXPECT_TRUE(contains(msg,
                         "<string>:3:1: <film> named \"sampler\": parameter \"sampler\" of "
                         "<sensor type=\"perspective\"> takes sampler, not a <film>"))
        << msg;
    msg = load_error(scene(sensor_xml() +
                           "<shape type=\"rectangle\">\n<bsdf type=\"diffuse\" "
                           "name=\"to_world\"/></shape>" +
                           kLight));
    EXPECT_TRUE(contains(msg,
                         "<string>:4:1: <bsdf> named \"to_world\": parameter \"to_world\" of "
                         "<shape type=\"rectangle\"> takes transform"))
        << msg;
}

// 6: properties written directly in <scene> are Mitsuba's acceleration settings: accepted
// (femto builds its own BVH); other names are unknown parameters.
TEST(MitsubaSyntax, SceneLevelProperties) {
    const std::string settings =
        "<integer name=\"kd_max_depth\" value=\"20\"/><float name=\"kd_traversal_cost\" "
        "value=\"10\"/><boolean name=\"embree_use_robust_intersections\" value=\"true\"/>";
    const int warnings = warning_count();
    expect_same_image(
        render_string(scene(settings + sensor_xml() + kRedBsdf + kShapeRefRed + kLight)),
        render_string(native_scene()), "scene properties", "none");
    // 0.6's camelCase names are upgraded like any other parameter.
    EXPECT_NO_THROW(load_scene_string(scene("<boolean name=\"kdParallelBuild\" value=\"true\"/>" +
                                                sensor_xml() + kShapeRefRed + kRedBsdf + kLight,
                                            "0.6.0")));
    EXPECT_EQ(warning_count(), warnings);  // notes, not warnings

    const std::string unknown = scene("\n<integer name=\"kd_max_dept\" value=\"3\"/>" +
                                      sensor_xml() + kRedBsdf + kShapeRefRed + kLight);
    std::string msg = load_error(unknown);
    EXPECT_TRUE(contains(msg,
                         "<string>:3:1: <scene> has no property \"kd_max_dept\" (did you "
                         "mean \"kd_max_depth\"?)"))
        << msg;
    LoadOptions lenient;
    lenient.lenient = true;
    EXPECT_NO_THROW(load_scene_string(unknown, lenient));
    EXPECT_EQ(warning_count(), warnings + 1);
    msg = load_error(scene("\n<float name=\"kd_clip\" value=\"1\"/>" + sensor_xml() + kRedBsdf +
                           kShapeRefRed + kLight));
    EXPECT_TRUE(contains(msg, "<string>:3:1: scene property \"kd_clip\" must be a <boolean>"))
        << msg;
}

// 7, 8: film and camera parameters of Mitsuba 0.6 and 3 that change nothing in femto's image.
TEST(MitsubaSyntax, AcceptedFilmAndCameraParameters) {
    const std::string film =
        "<boolean name=\"banner\" value=\"true\"/><boolean name=\"high_quality_edges\" "
        "value=\"true\"/><string name=\"component_format\" value=\"float16\"/>";
    const std::string camera = "<float name=\"focus_distance\" value=\"3\"/>";
    expect_same_image(
        render_string(scene(sensor_xml(camera, film) + kRedBsdf + kShapeRefRed + kLight)),
        render_string(native_scene()), "banner, high_quality_edges, focus_distance", "native");
    const std::string msg = load_error(scene(
        sensor_xml("", "\n<string name=\"component_format\" value=\"int8\"/>") + kShapeRefRed));
    EXPECT_TRUE(contains(msg, "<string>:3:1:")) << msg;
    EXPECT_TRUE(contains(msg, "component_format must be float16, float32 or uint32")) << msg;
}

// 8: Mitsuba 3's principal point offset: a pixel looks where the pixel `offset` image widths
// (heights) further used to, so the optical axis moves from the image centre to
// (0.5 - offset_x) W, (0.5 - offset_y) H.
TEST(MitsubaSyntax, PrincipalPointOffsetMovesTheOpticalAxis) {
    const double ox = 0.25, oy = -0.125;
    const std::string camera =
        "<float name=\"principal_point_offset_x\" value=\"0.25\"/>"
        "<float name=\"principal_point_offset_y\" value=\"-0.125\"/>";
    auto shifted = load_scene_string(scene(sensor_xml(camera) + kRedBsdf + kShapeRefRed + kLight));
    auto centred = load_scene_string(native_scene());
    const Sensor& s = shifted->sensor();
    const Sensor& c = centred->sensor();
    const float W = 16, H = 16;
    // The camera looks down -z from z = 4: the optical axis is (0, 0, -1).
    const Ray axis = s.sample_ray({float((0.5 - ox) * W), float((0.5 - oy) * H)}, {0.5f, 0.5f});
    EXPECT_NEAR(axis.d.x, 0.f, 1e-6f);
    EXPECT_NEAR(axis.d.y, 0.f, 1e-6f);
    EXPECT_NEAR(axis.d.z, -1.f, 1e-6f);
    const Ray centre = c.sample_ray({W / 2, H / 2}, {0.5f, 0.5f});
    EXPECT_NEAR(centre.d.z, -1.f, 1e-6f);
    // Every other pixel moves by the same offset.
    for (const Vec2 p : {Vec2{1.5f, 2.5f}, Vec2{13.f, 7.25f}}) {
        const Ray a = s.sample_ray(p, {0.5f, 0.5f});
        const Ray b = c.sample_ray({p.x + float(ox * W), p.y + float(oy * H)}, {0.5f, 0.5f});
        EXPECT_NEAR(a.d.x, b.d.x, 1e-6f);
        EXPECT_NEAR(a.d.y, b.d.y, 1e-6f);
        EXPECT_NEAR(a.d.z, b.d.z, 1e-6f);
    }
}

// Mitsuba 0.6's `bdpt` is femto's BDPT with Mitsuba's defaults (roulette from depth 5):
// maxDepth, rrDepth and lightImage keep their meaning, sampleDirect=false is ignored with a
// note (femto always samples emitters and the sensor directly). The same seed renders the
// same image as transient_bdpt given the same parameters.
TEST(MitsubaSyntax, BdptIsFemtosBdptWithMitsubaDefaults) {
    const std::string body = sensor_xml() + kRedBsdf + kShapeRefRed + kLight;
    for (const bool light_image : {true, false}) {
        SCOPED_TRACE(light_image ? "lightImage true" : "lightImage false");
        const std::string flag = light_image ? "true" : "false";
        const std::string old = scene(
            "<integrator type=\"bdpt\"><integer name=\"maxDepth\" value=\"3\"/><integer "
            "name=\"rrDepth\" value=\"2\"/><boolean name=\"lightImage\" value=\"" +
                flag + "\"/><boolean name=\"sampleDirect\" value=\"false\"/></integrator>" + body,
            "0.6.0");
        const std::string native = scene(
            "<integrator type=\"transient_bdpt\"><integer name=\"max_depth\" value=\"3\"/><integer "
            "name=\"rr_depth\" value=\"2\"/><boolean name=\"light_image\" value=\"" +
            flag + "\"/></integrator>" + body);
        expect_same_image(render_string(old), render_string(native), "0.6 bdpt", "transient_bdpt");
    }
    // Its own default: roulette from depth 5, where transient_bdpt has none.
    auto loaded = load_scene_string(scene("<integrator type=\"bdpt\"/>" + body, "0.6.0"));
    const auto& integrator = static_cast<const MonteCarloIntegrator&>(loaded->integrator());
    EXPECT_EQ(integrator.rr_depth(), 5);
    EXPECT_EQ(integrator.max_depth(), -1);
}

// Mitsuba's `volpath` (0.6 and 3) is femto's `path`, which renders media: the same image for a
// seed, with its parameters in either spelling.
TEST(MitsubaSyntax, VolpathIsFemtosPath) {
    const std::string body =
        "<medium type=\"homogeneous\" id=\"fog\"><float name=\"sigma_t\" value=\"0.3\"/>"
        "</medium>" +
        sensor_xml("<ref id=\"fog\"/>") + kRedBsdf + kShapeRefRed + kLight;
    const std::string native = scene(
        "<integrator type=\"path\"><integer name=\"max_depth\" value=\"4\"/><integer "
        "name=\"rr_depth\" value=\"2\"/></integrator>" +
        body);
    const std::string old = scene(
        "<integrator type=\"volpath\"><integer name=\"maxDepth\" value=\"4\"/><integer "
        "name=\"rrDepth\" value=\"2\"/></integrator>" +
            body,
        "0.6.0");
    const std::string v3 = scene(
        "<integrator type=\"volpath\"><integer name=\"max_depth\" value=\"4\"/><integer "
        "name=\"rr_depth\" value=\"2\"/></integrator>" +
        body);
    const auto reference = render_string(native);
    expect_same_image(render_string(old), reference, "0.6 volpath", "path");
    expect_same_image(render_string(v3), reference, "3.0 volpath", "path");
}
