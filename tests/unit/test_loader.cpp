// The XML loader: passes (include, default, $param, -D, version upgrade), references,
// transforms, value parsing and strict parameters.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "femto/bsdf.h"
#include "femto/input_file.h"
#include "femto/integrator.h"
#include "femto/log.h"
#include "femto/sensor.h"
#include "scene_util.h"
#include "xml/parser.h"

using namespace femto;
using femto::test::kRect;
using femto::test::load_error;
using femto::test::scene_xml;

TEST(Loader, LoadsMinimalScene) {
    auto scene = load_scene_string(scene_xml(kRect));
    ASSERT_TRUE(scene);
    EXPECT_EQ(scene->shapes().size(), 1u);
    EXPECT_EQ(scene->integrator().type_name(), "path");  // the default integrator
    EXPECT_EQ(scene->sensor().film().width(), 8);
}

TEST(Loader, UpgradesMitsuba06Names) {
    EXPECT_EQ(detail::upgrade_parameter_name("maxDepth"), "max_depth");
    EXPECT_EQ(detail::upgrade_parameter_name("toWorld"), "to_world");
    EXPECT_EQ(detail::upgrade_parameter_name("specularReflectance"), "specular_reflectance");
    EXPECT_EQ(detail::upgrade_parameter_name("intIOR"), "int_ior");
    EXPECT_EQ(detail::upgrade_parameter_name("fovAxis"), "fov_axis");
    EXPECT_EQ(detail::upgrade_parameter_name("max_depth"), "max_depth");
    EXPECT_EQ(detail::upgrade_plugin_type("sampler", "sobol"), "ldsampler");
    // A 0.6 file with camelCase names loads; the same names in a 3.x file are errors.
    const std::string body =
        "<integrator type=\"path\"><integer name=\"maxDepth\" value=\"3\"/></integrator>" +
        std::string(kRect);
    EXPECT_NO_THROW(load_scene_string(scene_xml(body, "0.6.0")));
    EXPECT_NE(load_error(scene_xml(body, "3.0.0")).find("did you mean \"max_depth\""),
              std::string::npos);
}

TEST(Loader, DefaultsSubstitutionAndDefines) {
    const std::string xml = scene_xml(
        "<default name=\"w\" value=\"16\"/>"
        "<sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" value=\"$w\"/>"
        "<integer name=\"height\" value=\"$w\"/></film></sensor>" +
        std::string(kRect));
    EXPECT_EQ(load_scene_string(xml)->sensor().film().width(), 16);
    LoadOptions opts;
    opts.defines = {{"w", "24"}};
    EXPECT_EQ(load_scene_string(xml, opts)->sensor().film().height(), 24);
    const std::string msg =
        load_error(scene_xml("<sensor type=\"perspective\"><film type=\"hdrfilm\"><integer "
                             "name=\"width\" value=\"$nope\"/>"
                             "</film></sensor>" +
                             std::string(kRect)));
    EXPECT_NE(msg.find("$nope is not defined"), std::string::npos) << msg;
    EXPECT_NE(msg.find("<string>:2:"), std::string::npos) << msg;  // file:line:col
}

TEST(Loader, UnusedDefineIsAnError) {
    // The scene's parameters are its <default> names and the $names it uses.
    const std::string xml = scene_xml(
        "<default name=\"width_px\" value=\"16\"/>"
        "<sensor type=\"perspective\"><film type=\"hdrfilm\">"
        "<integer name=\"width\" value=\"$width_px\"/>"
        "<integer name=\"height\" value=\"$height_px\"/></film></sensor>" +
        std::string(kRect));
    LoadOptions opts;
    opts.defines = {{"height_px", "8"}, {"widht_px", "24"}};
    const std::string msg = load_error(xml, opts);
    EXPECT_NE(msg.find("-D widht_px=24: the scene has no parameter \"widht_px\" (did you mean "
                       "\"width_px\"?)"),
              std::string::npos)
        << msg;
    EXPECT_NE(msg.find("$names): height_px, width_px"), std::string::npos) << msg;
    // A scene without parameters says so.
    opts.defines = {{"spp", "4"}};
    EXPECT_NE(load_error(scene_xml(kRect), opts).find("$names): (none)"), std::string::npos);
    // --lenient: a warning, and the scene loads.
    opts.lenient = true;
    opts.defines = {{"height_px", "8"}, {"widht_px", "24"}};
    const int warnings = warning_count();
    EXPECT_EQ(load_scene_string(xml, opts)->sensor().film().width(), 16);
    EXPECT_EQ(warning_count(), warnings + 1);
}

TEST(Loader, IncludeIsRelativeToTheIncludingFile) {
    const auto dir = test::temp_dir("include");
    std::filesystem::create_directories(dir / "parts" / "more");
    test::write_text(dir / "parts" / "a.xml",
                     "<scene version=\"0.6.0\"><include filename=\"more/b.xml\"/></scene>");
    test::write_text(dir / "parts" / "more" / "b.xml",
                     "<scene version=\"0.6.0\"><bsdf type=\"diffuse\" id=\"grey\"/></scene>");
    test::write_text(dir / "main.xml", scene_xml("<include filename=\"parts/a.xml\"/><shape "
                                                 "type=\"rectangle\"><ref id=\"grey\"/></shape>"));
    auto scene = load_scene((dir / "main.xml").string());
    EXPECT_EQ(scene->shapes()[0]->bsdf()->id(), "grey");
    // A missing include names the including file and line.
    test::write_text(dir / "bad.xml", scene_xml("<include filename=\"nothere.xml\"/>"));
    try {
        load_scene((dir / "bad.xml").string());
        FAIL();
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("bad.xml:3:"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("nothere.xml"), std::string::npos) << e.what();
    }
    // An include cycle is an error, not a hang.
    test::write_text(dir / "cycle.xml",
                     "<scene version=\"3.0.0\"><include filename=\"cycle.xml\"/></scene>");
    EXPECT_THROW(load_scene((dir / "cycle.xml").string()), SceneError);
}

TEST(Loader, RefAndAlias) {
    auto scene =
        load_scene_string(scene_xml("<bsdf type=\"diffuse\" id=\"a\"/><alias id=\"a\" as=\"b\"/>"
                                    "<shape type=\"rectangle\"><ref id=\"b\"/></shape>"));
    EXPECT_EQ(scene->shapes()[0]->bsdf()->id(), "a");
    const std::string msg =
        load_error(scene_xml("<shape type=\"rectangle\"><ref id=\"whte\"/></shape>"
                             "<bsdf type=\"diffuse\" id=\"white\"/>"));
    EXPECT_NE(msg.find("no object with id \"whte\""), std::string::npos) << msg;
    EXPECT_NE(
        load_error(scene_xml("<bsdf type=\"diffuse\" id=\"x\"/><bsdf type=\"diffuse\" id=\"x\"/>" +
                             std::string(kRect)))
            .find("defined twice"),
        std::string::npos);
}

TEST(Loader, StrictParameters) {
    // Unknown parameter: located error with the closest valid name.
    std::string msg = load_error(scene_xml(
        "<shape type=\"rectangle\"><boolean name=\"flip_normal\" value=\"true\"/></shape>"));
    EXPECT_NE(msg.find("<string>:3:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("did you mean \"flip_normals\""), std::string::npos) << msg;
    // ... which --lenient turns into a warning.
    LoadOptions lenient;
    lenient.lenient = true;
    EXPECT_NO_THROW(load_scene_string(
        scene_xml(
            "<shape type=\"rectangle\"><boolean name=\"flip_normal\" value=\"true\"/></shape>"),
        lenient));
    // Wrong type.
    msg = load_error(scene_xml(
        "<shape type=\"rectangle\"><string name=\"flip_normals\" value=\"yes\"/></shape>"));
    EXPECT_NE(msg.find("must be a boolean, but a string was given"), std::string::npos) << msg;
    // ... with the right article.
    msg =
        load_error(scene_xml("<integrator type=\"path\"><float name=\"max_depth\" "
                             "value=\"2.5\"/></integrator>" +
                             std::string(kRect)));
    EXPECT_NE(msg.find("must be an integer, but a float was given"), std::string::npos) << msg;
    // Unknown plugin, with suggestion.
    msg = load_error(scene_xml("<shape type=\"rectangel\"/>"));
    EXPECT_NE(msg.find("unknown <shape> plugin \"rectangel\" (did you mean \"rectangle\"?)"),
              std::string::npos)
        << msg;
    // An empty type is named as such, not "corrected" to some short plugin name like "hg".
    msg = load_error(scene_xml("<shape type=\"rectangle\"><bsdf type=\"\"/></shape>"));
    EXPECT_NE(msg.find("<string>:3:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("the <bsdf> type is empty"), std::string::npos) << msg;
    EXPECT_EQ(msg.find("did you mean"), std::string::npos) << msg;
    // A plugin of the wrong kind.
    msg = load_error(scene_xml("<shape type=\"diffuse\"/>"));
    EXPECT_NE(msg.find("is a <bsdf> plugin, but it is used as a <shape>"), std::string::npos)
        << msg;
    msg = load_error(scene_xml("<emitter type=\"path\"/>" + std::string(kRect)));
    EXPECT_NE(msg.find("is an <integrator> plugin, but it is used as an <emitter>"),
              std::string::npos)
        << msg;
    // Unknown tag and attribute.
    msg =
        load_error(scene_xml("<shape type=\"rectangle\"><colour name=\"x\" value=\"1\"/></shape>"));
    EXPECT_NE(msg.find("unknown tag <colour>"), std::string::npos) << msg;
    msg = load_error(scene_xml("<shape type=\"rectangle\" idd=\"x\"/>"));
    EXPECT_NE(msg.find("unknown attribute \"idd\""), std::string::npos) << msg;
    // A nested object nobody uses.
    msg = load_error(scene_xml("<shape type=\"rectangle\"><rfilter type=\"box\"/></shape>"));
    EXPECT_NE(msg.find("does not use the nested object"), std::string::npos) << msg;
}

TEST(Loader, ParameterGivenTwiceIsAnError) {
    std::string msg =
        load_error(scene_xml("<sensor type=\"perspective\">\n<float name=\"fov\" value=\"30\"/>\n"
                             "<float name=\"fov\" value=\"40\"/></sensor>" +
                             std::string(kRect)));
    EXPECT_NE(msg.find("<string>:4:1: \"perspective\": parameter \"fov\" is given twice "
                       "(first at <string>:3:1)"),
              std::string::npos)
        << msg;
    // Whatever the types, and for named objects too.
    msg = load_error(
        scene_xml("<shape type=\"rectangle\"><boolean name=\"flip_normals\" value=\"true\"/>"
                  "<string name=\"flip_normals\" value=\"x\"/></shape>"));
    EXPECT_NE(msg.find("parameter \"flip_normals\" is given twice"), std::string::npos) << msg;
    msg = load_error(
        scene_xml("<medium type=\"homogeneous\" id=\"fog\"/><shape type=\"cube\"><bsdf "
                  "type=\"null\"/><ref name=\"interior\" id=\"fog\"/><ref name=\"interior\" "
                  "id=\"fog\"/></shape>"));
    EXPECT_NE(msg.find("parameter \"interior\" is given twice"), std::string::npos) << msg;
}

TEST(Loader, AtMostOneChildOfAKind) {
    // Properties::child(): located at the second child, naming the tag.
    std::string msg = load_error(scene_xml(
        "<shape type=\"rectangle\">\n<bsdf type=\"diffuse\"/>\n<bsdf type=\"null\"/></shape>"));
    EXPECT_NE(msg.find("<string>:5:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("\"rectangle\": give at most one <bsdf>"), std::string::npos) << msg;
    msg =
        load_error(scene_xml("<sensor type=\"perspective\"><film type=\"hdrfilm\"/><film "
                             "type=\"hdrfilm\"/></sensor>" +
                             std::string(kRect)));
    EXPECT_NE(msg.find("give at most one <film>"), std::string::npos) << msg;
    msg =
        load_error(scene_xml("<medium type=\"homogeneous\" id=\"m\"><phase type=\"hg\"/>"
                             "<phase type=\"isotropic\"/></medium>"));
    EXPECT_NE(msg.find("give at most one <phase>"), std::string::npos) << msg;
}

TEST(Loader, BadValues) {
    auto film = [](const std::string& w) {
        return scene_xml(
            "<sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" value=\"" +
            w + "\"/></film></sensor>" + std::string(kRect));
    };
    EXPECT_NE(load_error(film("0")).find("width must be in [1, 65536]"), std::string::npos);
    EXPECT_NE(load_error(film("-5")).find("width must be in"), std::string::npos);
    EXPECT_NE(load_error(film("1e9")).find("not an integer"), std::string::npos);
    EXPECT_NE(load_error(film("99999999999999999999")).find("out of range"), std::string::npos);
    EXPECT_NE(
        load_error(
            scene_xml("<sensor type=\"perspective\"><float name=\"fov\" value=\"nan\"/></sensor>" +
                      std::string(kRect)))
            .find("non-finite"),
        std::string::npos);
    EXPECT_NE(
        load_error(
            scene_xml("<sensor type=\"perspective\"><float name=\"fov\" value=\"inf\"/></sensor>" +
                      std::string(kRect)))
            .find("non-finite"),
        std::string::npos);
    EXPECT_NE(
        load_error(
            scene_xml("<shape type=\"rectangle\"><transform name=\"to_world\"><scale x=\"0\"/>"
                      "</transform></shape>"))
            .find("degenerate transform"),
        std::string::npos);
    EXPECT_NE(
        load_error(
            scene_xml(
                "<shape type=\"rectangle\"><transform name=\"to_world\">"
                "<lookat origin=\"0,0,0\" target=\"0,0,0\" up=\"0,1,0\"/></transform></shape>"))
            .find("degenerate transform"),
        std::string::npos);
    EXPECT_NE(
        load_error(
            scene_xml("<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"1, 2\"/></bsdf>"))
            .find("needs 1 or 3 numbers"),
        std::string::npos);
}

TEST(Loader, ProjectiveMatrixIsRefused) {
    const std::string msg = load_error(scene_xml(
        "<shape type=\"rectangle\"><transform name=\"to_world\">\n<matrix value=\"1 0 0 0 "
        "0 1 0 0 0 0 1 0 0 0 0.5 1\"/></transform></shape>"));
    EXPECT_NE(msg.find("<string>:4:1: <matrix> has the last row 0 0 0.5 1, not 0 0 0 1"),
              std::string::npos)
        << msg;
    EXPECT_NO_THROW(load_scene_string(
        scene_xml("<shape type=\"rectangle\"><transform name=\"to_world\"><matrix value=\"2 0 0 1 "
                  "0 2 0 0 0 0 2 0 0 0 0 1\"/></transform></shape>")));
}

// Far beyond 1e9 scene units single-precision ray tracing breaks down (black images, Embree
// aborting on ray origins past 1.8e18): such scenes are refused where they are written.
TEST(Loader, CoordinatesBeyondTheSceneRangeAreRefused) {
    auto sensor_at = [](const std::string& transform) {
        return scene_xml("<sensor type=\"perspective\">\n<transform name=\"to_world\">" +
                         transform + "</transform></sensor>" + std::string(kRect));
    };
    std::string msg = load_error(sensor_at("<translate x=\"2e18\"/>"));
    EXPECT_NE(msg.find("<string>:3:1: \"perspective\": to_world's origin lies at (2e+18, 0, 0), "
                       "beyond femto's limit of +-1e+09 scene units"),
              std::string::npos)
        << msg;
    // A lookat names the coordinate at fault, whether a float could hold it or not.
    for (const std::string origin : {"2e18", "1e39"}) {
        msg = load_error(sensor_at("<lookat origin=\"" + origin +
                                   ", 0, 0\" target=\"0, 0, 0\" up=\"0, 1, 0\"/>"));
        EXPECT_NE(msg.find("<lookat> origin lies at (" + origin.substr(0, 1) + "e+"),
                  std::string::npos)
            << msg;
    }
    msg =
        load_error(sensor_at("<lookat origin=\"0, 0, 1\" target=\"0, 0, 0\" up=\"0, 1e39, 0\"/>"));
    EXPECT_NE(msg.find("up: 1e+39 is beyond the range of single precision"), std::string::npos)
        << msg;
    msg = load_error(
        scene_xml("<shape type=\"rectangle\">\n<transform name=\"to_world\"><scale value=\"3e9\"/>"
                  "</transform></shape>"));
    EXPECT_NE(
        msg.find("<string>:3:1: vertex 0 (0-based) of the mesh, in the scene, lies at (-3e+09"),
        std::string::npos)
        << msg;
    msg = load_error(
        scene_xml("<shape type=\"sphere\"><float name=\"radius\" value=\"2e9\"/></shape>"));
    EXPECT_NE(msg.find("a sphere of radius 2e+09"), std::string::npos) << msg;
    msg = load_error(
        scene_xml("<emitter type=\"point\"><point name=\"position\" x=\"1e12\" y=\"0\" z=\"0\"/>"
                  "</emitter>"));
    EXPECT_NE(msg.find("the point light lies at (1e+12, 0, 0)"), std::string::npos) << msg;
    msg = load_error(scene_xml(
        "<sensor type=\"orthographic\"><transform name=\"to_world\"><scale value=\"1e10\"/>"
        "</transform></sensor>" +
        std::string(kRect)));
    EXPECT_NE(msg.find("a corner of the view lies at"), std::string::npos) << msg;
    msg = load_error(scene_xml(
        "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5, 1e39, 0.5\"/></bsdf>"));
    EXPECT_NE(msg.find("rgb: 1e+39 is beyond the range of single precision"), std::string::npos)
        << msg;
    // Large scenes within the range load.
    EXPECT_NO_THROW(load_scene_string(scene_xml(
        "<sensor type=\"perspective\"><transform name=\"to_world\"><lookat origin=\"0, 0, "
        "9e8\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform></sensor><shape "
        "type=\"rectangle\"><transform name=\"to_world\"><scale value=\"5e8\"/></transform>"
        "</shape>")));
}

// Each scene body gives a SceneError at `where` whose message holds `text`.
void expect_errors(const std::vector<std::string>& bodies, const std::string& where,
                   const std::string& text) {
    for (const std::string& body : bodies) {
        const std::string msg = load_error(scene_xml(body));
        EXPECT_NE(msg.find(where), std::string::npos) << msg;
        EXPECT_NE(msg.find(text), std::string::npos) << msg;
    }
}

TEST(Loader, NegativeReflectanceIsRefused) {
    expect_errors(
        {"<bsdf type=\"diffuse\">\n<rgb name=\"reflectance\" value=\"0.5, -0.1, 0.5\"/></bsdf>",
         "<bsdf type=\"plastic\">\n<float name=\"diffuse_reflectance\" value=\"-1\"/></bsdf>",
         "<bsdf type=\"diffuse\"><texture type=\"checkerboard\" name=\"reflectance\">\n<rgb "
         "name=\"color0\" value=\"-0.2\"/></texture></bsdf>"},
        "<string>:4:1:", "must not be negative");
    EXPECT_NO_THROW(load_scene_string(scene_xml(
        "<bsdf type=\"diffuse\" id=\"b\"><rgb name=\"reflectance\" value=\"0, 0.5, 1\"/></bsdf>" +
        std::string(kRect))));
}

// Emission near float's limit (3.4e38) overflowed to infinity in the outputs.
TEST(Loader, AbsurdEmissionIsRefused) {
    expect_errors(
        {"<shape type=\"rectangle\"><emitter type=\"area\">\n<rgb name=\"radiance\" "
         "value=\"3e38\"/></emitter></shape>",
         "<emitter type=\"point\">\n<rgb name=\"intensity\" value=\"1, 1e31, 1\"/></emitter>",
         "<emitter type=\"spot\">\n<float name=\"intensity\" value=\"2e30\"/></emitter>",
         "<emitter type=\"collimated\"><float name=\"radius\" value=\"0.1\"/>\n<rgb "
         "name=\"power\" value=\"1e35\"/></emitter>"},
        "<string>:4:1:", "is beyond femto's limit of 1e+30");
    const std::string msg = load_error(scene_xml(
        "<emitter type=\"point\"><rgb name=\"intensity\" value=\"1, -1, 1\"/></emitter>"));
    EXPECT_NE(msg.find("the intensity must not be negative"), std::string::npos) << msg;
    EXPECT_NO_THROW(load_scene_string(
        scene_xml("<emitter type=\"point\"><rgb name=\"intensity\" value=\"1e29\"/></emitter>")));
}

// Errors found once the scene is built (preprocess, prepare) point at the element concerned.
TEST(Loader, ErrorsBeforeRenderingAreLocated) {
    auto render_error = [](const std::string& xml) {
        auto scene = load_scene_string(xml);
        RenderOptions options;
        options.spp = 1;
        options.threads = 1;
        try {
            render(*scene, options);
        } catch (const SceneError& e) {
            return std::string(e.what());
        }
        ADD_FAILURE() << "no error for\n" << xml;
        return std::string();
    };
    const std::string fog = "<medium type=\"homogeneous\"/>";
    std::string msg =
        render_error(scene_xml("\n<integrator type=\"direct\"/><sensor "
                               "type=\"perspective\">" +
                               fog + "</sensor>" + kRect));
    EXPECT_NE(msg.find("<string>:3:1: the direct integrator does not render participating media"),
              std::string::npos)
        << msg;
    msg = render_error(
        scene_xml("<integrator type=\"transient_path\"><integer name=\"max_depth\" value=\"4\"/>\n"
                  "<distance type=\"exponential\"/></integrator><sensor type=\"perspective\">" +
                  fog + "</sensor>" + kRect));
    EXPECT_NE(msg.find("<string>:3:1: distance sampling \"exponential\""), std::string::npos)
        << msg;
    msg = render_error(scene_xml(
        "<sensor type=\"perspective\"><film type=\"hdrfilm\">\n<rfilter type=\"gaussian\"><float "
        "name=\"stddev\" value=\"40\"/></rfilter></film></sensor>" +
        std::string(kRect)));
    EXPECT_NE(msg.find("<string>:3:1: the reconstruction filter's radius"), std::string::npos)
        << msg;
    // Unbounded paths into a steady film: located at max_depth.
    msg = render_error(
        scene_xml("<integrator type=\"transient_path\">\n<integer name=\"max_depth\" value=\"-1\"/>"
                  "</integrator>" +
                  std::string(kRect)));
    EXPECT_NE(msg.find("<string>:4:1: transient_path with max_depth=-1"), std::string::npos) << msg;
    EXPECT_NE(msg.find("needs a time window"), std::string::npos) << msg;
}

TEST(Loader, MalformedAndEmpty) {
    std::string msg =
        load_error("<scene version=\"3.0.0\">\n  <shape type=\"rectangle\">\n</scene>");
    EXPECT_NE(msg.find("malformed XML"), std::string::npos) << msg;
    EXPECT_NE(msg.find("<string>:3:"), std::string::npos) << msg;
    EXPECT_NE(
        load_error("<scene version=\"3.0.0\"><sensor type=\"perspective\"/></scene>").find("empty"),
        std::string::npos);
    EXPECT_NE(load_error("<scene version=\"3.0.0\"></scene>").find("no <sensor>"),
              std::string::npos);
    EXPECT_NE(load_error("<scene></scene>").find("version"), std::string::npos);
    EXPECT_NE(load_error("<notascene version=\"3.0.0\"/>").find("must be <scene>"),
              std::string::npos);
    EXPECT_NE(load_error("").find("holds no XML element"), std::string::npos);
}

TEST(Loader, DeepNestingIsAnErrorNotAStackOverflow) {
    auto nested = [](int depth, const std::string& inner) {
        std::string xml;
        for (int i = 0; i < depth; ++i) xml += "<bsdf type=\"twosided\">";
        xml += inner;
        for (int i = 0; i < depth; ++i) xml += "</bsdf>";
        return xml;
    };
    for (const int depth : {7000, 100000}) {
        const std::string msg =
            load_error("<scene version=\"3.0.0\">" + nested(depth, "") + "</scene>");
        EXPECT_NE(msg.find("<string>:1:"), std::string::npos) << msg;
        EXPECT_NE(msg.find("nested more than 100 levels deep"), std::string::npos) << msg;
    }
    // An included file's elements count from the depth of the <include>.
    const auto dir = test::temp_dir("deep-include");
    test::write_text(dir / "part.xml", "<scene version=\"3.0.0\">" + nested(60, "") + "</scene>");
    test::write_text(
        dir / "main.xml",
        "<scene version=\"3.0.0\">" + nested(50, "<include filename=\"part.xml\"/>") + "</scene>");
    try {
        load_scene((dir / "main.xml").string());
        ADD_FAILURE() << "no error";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("part.xml:1:"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("nested more than 100"), std::string::npos)
            << e.what();
    }
}

TEST(Loader, NothingBesidesTheRootElement) {
    const std::string scene = scene_xml(kRect);
    std::string msg = load_error(scene + "<shape type=\"sphere\"/>\n");
    EXPECT_NE(msg.find("<shape> outside the root element <scene>"), std::string::npos) << msg;
    EXPECT_NE(msg.find("<string>:5:1:"), std::string::npos) << msg;
    msg = load_error(scene + "\n  trailing words\n");
    EXPECT_NE(msg.find("<string>:6:3: text outside the root element"), std::string::npos) << msg;
    msg = load_error("stray<scene version=\"3.0.0\"/>");
    EXPECT_NE(msg.find("text outside the root element"), std::string::npos) << msg;
    // Comments, the declaration and blank space around the root are fine.
    EXPECT_NO_THROW(
        load_scene_string("<?xml version=\"1.0\"?>\n<!-- a -->\n" + scene + "<!-- b -->\n\n"));
}

TEST(Loader, MissingMeshFileIsLocated) {
    const std::string msg = load_error(
        scene_xml("<shape type=\"obj\"><string name=\"filename\" value=\"no/such.obj\"/></shape>"));
    EXPECT_NE(msg.find("<string>:3:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("such.obj"), std::string::npos) << msg;
}

// A FIFO blocks whoever opens it and a device such as /dev/zero never ends: every reader of a
// file that a scene names refuses both, with the location of the name.
TEST(Loader, InputFilesMustBeRegularFiles) {
    const auto dir = test::temp_dir("input-files");
    const std::string fifo = (dir / "fifo").string();
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    for (const std::string& path : {fifo, std::string("/dev/zero")})
        for (const std::string& xml :
             {"<shape type=\"obj\">\n<string name=\"filename\" value=\"" + path + "\"/></shape>",
              "<shape type=\"ply\">\n<string name=\"filename\" value=\"" + path + "\"/></shape>",
              "<shape type=\"rectangle\"><bsdf type=\"diffuse\"><texture type=\"bitmap\" "
              "name=\"reflectance\">\n<string name=\"filename\" value=\"" +
                  path + "\"/></texture></bsdf></shape>",
              "<medium type=\"heterogeneous\" id=\"m\">\n<string name=\"density\" value=\"" + path +
                  "\"/></medium>" + std::string(kRect),
              "\n<include filename=\"" + path + "\"/>" + std::string(kRect)}) {
            const std::string msg = load_error(scene_xml(xml));
            EXPECT_NE(msg.find("<string>:4:1:"), std::string::npos) << msg;
            EXPECT_NE(msg.find("\"" + path + "\""), std::string::npos) << msg;
            EXPECT_NE(msg.find("not a regular file"), std::string::npos) << msg;
        }
    EXPECT_THROW(load_scene(fifo), SceneError);

    // Reads stop at the size the file had when it was opened.
    test::write_text(dir / "data.txt", "0123456789");
    InputFile file((dir / "data.txt").string(), SourceLocation{"s.xml", 1, 2});
    EXPECT_EQ(file.size(), 10u);
    char head[4];
    EXPECT_EQ(file.read(head, sizeof head), 4u);
    test::write_text(dir / "data.txt", "0123456789 and more");  // grows meanwhile
    EXPECT_EQ(file.read_rest(), "456789");
    EXPECT_EQ(file.read(head, sizeof head), 0u);
    try {
        InputFile missing((dir / "nothere.obj").string(), SourceLocation{"s.xml", 3, 4});
        ADD_FAILURE() << "no error";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("s.xml:3:4: cannot open"), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("nothere.obj\": no such file"), std::string::npos)
            << e.what();
    }
    EXPECT_EQ(input_file_problem(dir.string()), "it is a directory");
    EXPECT_EQ(input_file_problem((dir / "data.txt").string()), "");
    std::filesystem::remove_all(dir);
}

TEST(Loader, LazyPluginLoading) {
    // The registry is per process: only what this scene opened counts (ctest runs each test in
    // a process of its own, where that is every plugin; a whole-binary run may have opened
    // others before).
    const std::vector<std::string> before = loaded_plugin_files();
    load_scene_string(scene_xml(kRect));
    const std::vector<std::string> after = loaded_plugin_files();
    ASSERT_GE(after.size(), before.size());
    if (before.empty()) {
        EXPECT_FALSE(after.empty()) << "the scene opened no plugin at all";
    }
    EXPECT_TRUE(std::equal(before.begin(), before.end(), after.begin()));
    for (auto it = after.begin() + std::ptrdiff_t(before.size()); it != after.end(); ++it) {
        const std::string& f = *it;
        EXPECT_EQ(f.find("roughconductor"), std::string::npos)
            << "a plugin the scene never names was loaded: " << f;
        EXPECT_EQ(f.find("ply.so"), std::string::npos) << f;
    }
}

TEST(Loader, PluginDirsMustBeFolders) {
    // A --plugin-dir that is missing or a file is an error naming it, not an empty folder.
    const std::filesystem::path dir = femto::test::temp_dir("plugin-dirs");
    femto::test::write_text(dir / "afile", "");
    LoadOptions opts;
    opts.plugin_dirs = {(dir / "missing").string()};
    EXPECT_NE(
        load_error(scene_xml(kRect), opts)
            .find("plugin folder \"" + opts.plugin_dirs[0] + "\" (--plugin-dir) does not exist"),
        std::string::npos);
    opts.plugin_dirs = {(dir / "afile").string()};
    EXPECT_NE(load_error(scene_xml(kRect), opts).find("is not a folder"), std::string::npos);
    // An empty folder is fine, and searched before femto's own plugins.
    opts.plugin_dirs = {dir.string()};
    EXPECT_NO_THROW(load_scene_string(scene_xml(kRect), opts));
    EXPECT_EQ(plugin_search_path(opts).front(), dir.string());
}
