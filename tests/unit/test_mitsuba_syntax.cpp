// Mitsuba XML syntax that real scene files use (docs/compatibility.md, "XML syntax"): each
// feature renders the same image as a femto-native equivalent (same seed), and its errors are
// located.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

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

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

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
