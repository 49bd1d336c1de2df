// Scenes written for the peer transient renderers (docs/compatibility.md, "Peer transient
// renderers"): mitransient's transient_hdr_film, transient_path and transient_prbvolpath, and
// mitsuba2-transient's streakhdrfilm and transientpath render the same cube, bit for bit, as
// the femto-native scene they stand for (same seed); their bad values are SceneErrors located
// at the element (the CLI's exit code 2).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "femto/integrator.h"
#include "femto/scene.h"
#include "femto/sensor.h"
#include "femto/tfilter.h"
#include "scene_util.h"

using namespace femto;
using femto::test::load_error;
using femto::testing::Cube;
using femto::testing::render_cube;

namespace {

// A diffuse square at z = 0 lit by a point light, seen from z = 2.5: camera paths arrive
// between about 3.5 and 4.5 (optical length), their first segment being 2.5 to 2.9 long.
const std::string kCamera =
    "<float name=\"fov\" value=\"50\"/>"
    "<transform name=\"to_world\"><lookat origin=\"0,0,2.5\" target=\"0,0,0\" up=\"0,1,0\"/>"
    "</transform>"
    "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"4\"/></sampler>\n";
const std::string kWorld =
    "<bsdf type=\"diffuse\" id=\"grey\"><rgb name=\"reflectance\" value=\"0.8,0.5,0.3\"/></bsdf>\n"
    "<shape type=\"rectangle\"><ref id=\"grey\"/></shape>\n"
    "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.2\"/>"
    "<translate x=\"0.6\" y=\"-0.5\" z=\"0.6\"/></transform>"
    "<emitter type=\"area\"><rgb name=\"radiance\" value=\"3\"/></emitter></shape>\n"
    "<emitter type=\"point\"><point name=\"position\" x=\"0.3\" y=\"0.2\" z=\"1\"/>"
    "<rgb name=\"intensity\" value=\"2\"/></emitter>\n";

std::string scene(const std::string& version, const std::string& integrator,
                  const std::string& film, const std::string& world = kWorld) {
    return "<scene version=\"" + version + "\">\n" + integrator +
           "\n<sensor type=\"perspective\">" + kCamera + film + "\n</sensor>\n" + world +
           "</scene>\n";
}

std::string param(const char* tag, const std::string& name, const std::string& value) {
    return "<" + std::string(tag) + " name=\"" + name + "\" value=\"" + value + "\"/>";
}

// femto's own film: `extra` holds world_time and the <tfilter>.
std::string native_film(int bins, double bin_width, double start, const std::string& extra,
                        const std::string& rfilter = "<rfilter type=\"box\"/>") {
    return "<film type=\"transient\">" + param("integer", "width", "16") +
           param("integer", "height", "12") + param("integer", "bins", std::to_string(bins)) +
           param("float", "bin_width", test::xml_number(bin_width)) +
           param("float", "start", test::xml_number(start)) + rfilter + extra + "</film>";
}
const std::string kHistogram = "<tfilter type=\"histogram\"/>";

std::string native_path(int max_depth, int rr_depth) {
    return "<integrator type=\"transient_path\">" +
           param("integer", "max_depth", std::to_string(max_depth)) +
           param("integer", "rr_depth", std::to_string(rr_depth)) + "</integrator>";
}

// mitransient's film; `time` holds its time parameters.
std::string mitransient_film(const std::string& time,
                             const std::string& rfilter = "<rfilter type=\"box\"/>") {
    return "<film type=\"transient_hdr_film\">\n" + param("integer", "width", "16") +
           param("integer", "height", "12") + "\n" + time + "\n" + rfilter + "\n</film>";
}
std::string mitransient_time(int bins, double bin_width, double start) {
    return param("integer", "temporal_bins", std::to_string(bins)) +
           param("float", "bin_width_opl", test::xml_number(bin_width)) +
           param("float", "start_opl", test::xml_number(start));
}

Cube render(const std::string& xml, const std::string& name) {
    auto s = load_scene_string(xml, {}, ".");
    return render_cube(*s, 23, name);
}

double total(const Cube& c) {
    double t = 0;
    for (float v : c.data) t += v;
    return t;
}

// Same shape and the same bits; the cube holds light (the comparison is not vacuous).
void expect_same_cube(const Cube& peer, const Cube& native) {
    ASSERT_EQ(peer.H, native.H);
    ASSERT_EQ(peer.W, native.W);
    ASSERT_EQ(peer.T, native.T);
    ASSERT_EQ(peer.C, native.C);
    EXPECT_TRUE(peer.data == native.data);
    EXPECT_GT(total(native), 0.0);
}

// 1-based line of the first occurrence of `part` in `text`.
int line_of(const std::string& text, const std::string& part) {
    const size_t at = text.find(part);
    EXPECT_NE(at, std::string::npos) << part;
    int line = 1;
    for (size_t i = 0; i < at && i < text.size(); ++i) line += text[i] == '\n';
    return line;
}

// The error `xml` gives is located at the line holding `where` and says `what`.
void expect_error_at(const std::string& xml, const std::string& where, const std::string& what) {
    const std::string msg = load_error(xml);
    const std::string loc = "<string>:" + std::to_string(line_of(xml, where)) + ":";
    EXPECT_NE(msg.find(loc), std::string::npos) << "expected " << loc << " in: " << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << "expected \"" << what << "\" in: " << msg;
}

std::string mitransient_path(const std::string& params) {
    return "<integrator type=\"transient_path\">\n" + params + "\n</integrator>";
}

}  // namespace

// The film's temporal_bins, bin_width_opl and start_opl are femto's bins, bin_width and start
// (both optical path length in scene units); the cube is [H, W, T, C] as mitransient's.
TEST(PeerTransient, MitransientFilmIsFemtosTransientFilm) {
    const Cube peer = render(scene("3.0.0",
                                   mitransient_path(param("integer", "max_depth", "4") +
                                                    param("string", "temporal_filter", "box")),
                                   mitransient_film(mitransient_time(40, 0.1, 2.0))),
                             "mi");
    const Cube native =
        render(scene("3.0.0", native_path(4, 5), native_film(40, 0.1, 2.0, kHistogram)), "native");
    expect_same_cube(peer, native);
    EXPECT_EQ(peer.H, 12);  // height first, as mitransient's (H, W, T, C)
    EXPECT_EQ(peer.W, 16);
    EXPECT_EQ(peer.T, 40);
}

// mitransient's defaults: 2048 bins of 0.003 from 0, max_depth 6, rr_depth 5, and the time
// filter left empty (the film's rfilter in space, a histogram in time).
TEST(PeerTransient, MitransientDefaults) {
    const Cube peer = render(scene("3.0.0", "<integrator type=\"transient_path\"/>",
                                   mitransient_film("", "<rfilter type=\"tent\"/>")),
                             "mi");
    const Cube native =
        render(scene("3.0.0", native_path(6, 5),
                     native_film(2048, 0.003, 0.0, kHistogram, "<rfilter type=\"tent\"/>")),
               "native");
    expect_same_cube(peer, native);
    // The defaults are mitransient's, not femto's own (no depth limit, no roulette), which this
    // open scene could not tell apart by its cube.
    auto loaded = load_scene_string(
        scene("3.0.0", "<integrator type=\"transient_path\"/>", mitransient_film("")), {}, ".");
    const auto& integ = dynamic_cast<const MonteCarloIntegrator&>(loaded->integrator());
    EXPECT_EQ(integ.max_depth(), 6);
    EXPECT_EQ(integ.rr_depth(), 5);
    const auto& film = dynamic_cast<const TimeResolvedFilm&>(loaded->sensor().film());
    EXPECT_EQ(film.grid().bins, 2048);
    EXPECT_EQ(film.grid().bin_width, 0.003);
    EXPECT_EQ(film.grid().start, 0.0);
    auto volumetric = load_scene_string(
        scene("3.0.0", "<integrator type=\"transient_prbvolpath\"/>", mitransient_film("")), {},
        ".");
    EXPECT_EQ(dynamic_cast<const MonteCarloIntegrator&>(volumetric->integrator()).max_depth(), -1);
}

// camera_unwarp removes the camera segment: femto's world_time. Off, the film records camera
// time, as femto does by default.
TEST(PeerTransient, CameraUnwarpIsWorldTime) {
    const std::string time = mitransient_time(60, 0.1, 0.0);
    const Cube on =
        render(scene("3.0.0", mitransient_path(param("boolean", "camera_unwarp", "true")),
                     mitransient_film(time)),
               "mi-on");
    const Cube off =
        render(scene("3.0.0", mitransient_path(param("boolean", "camera_unwarp", "false")),
                     mitransient_film(time)),
               "mi-off");
    const std::string world = param("boolean", "world_time", "true") + kHistogram;
    expect_same_cube(on, render(scene("3.0.0", native_path(6, 5), native_film(60, 0.1, 0.0, world)),
                                "native-on"));
    expect_same_cube(
        off, render(scene("3.0.0", native_path(6, 5), native_film(60, 0.1, 0.0, kHistogram)),
                    "native-off"));
    EXPECT_FALSE(on.data == off.data);  // unwarped light arrives 2.5 to 2.9 earlier
    // As in mitransient, the emitter the camera sees directly arrives at 0 once unwarped (bin
    // 0), and about 2 later in camera time.
    double first_bin_on = 0, first_bin_off = 0;
    for (int y = 0; y < on.H; ++y)
        for (int x = 0; x < on.W; ++x) {
            first_bin_on += on.energy(y, x, 0);
            first_bin_off += off.energy(y, x, 0);
        }
    EXPECT_GT(first_bin_on, 0.0);
    EXPECT_EQ(first_bin_off, 0.0);
}

// temporal_filter="gaussian" with gaussian_stddev (bins) is a fixed Gaussian kernel in time:
// femto's kernel filter, alpha 1, half-width 3 standard deviations.
TEST(PeerTransient, MitransientGaussianTemporalFilter) {
    const Cube peer = render(scene("3.0.0",
                                   mitransient_path(param("string", "temporal_filter", "gaussian") +
                                                    param("float", "gaussian_stddev", "1.5")),
                                   mitransient_film(mitransient_time(40, 0.1, 2.0))),
                             "mi");
    const std::string kernel = "<tfilter type=\"kernel\">" + param("string", "kernel", "gaussian") +
                               param("float", "alpha", "1") +
                               param("float", "bandwidth", test::xml_number(3 * 1.5 * 0.1)) +
                               "</tfilter>";
    expect_same_cube(
        peer,
        render(scene("3.0.0", native_path(6, 5), native_film(40, 0.1, 2.0, kernel)), "native"));
}

// transient_prbvolpath renders media: femto's transient_path (which does), with mitransient's
// defaults for it (max_depth -1, rr_depth 5).
TEST(PeerTransient, TransientPrbVolpathInAMedium) {
    const std::string world =
        "<medium type=\"homogeneous\" id=\"fog\"><float name=\"sigma_t\" value=\"0.8\"/>"
        "<rgb name=\"albedo\" value=\"0.7\"/></medium>\n"
        "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"0.5\"/>"
        "<translate z=\"0.6\"/></transform><bsdf type=\"null\"/>"
        "<ref name=\"interior\" id=\"fog\"/></shape>\n" +
        kWorld;
    const std::string time = mitransient_time(40, 0.1, 2.0);
    const Cube peer = render(scene("3.0.0", "<integrator type=\"transient_prbvolpath\"/>",
                                   mitransient_film(time), world),
                             "mi");
    const Cube native = render(
        scene("3.0.0", native_path(-1, 5), native_film(40, 0.1, 2.0, kHistogram), world), "native");
    expect_same_cube(peer, native);
    // The fog is there: the same scene without it differs.
    EXPECT_FALSE(
        peer.data ==
        render(scene("3.0.0", native_path(-1, 5), native_film(40, 0.1, 2.0, kHistogram)), "clear")
            .data);
}

// mitsuba2-transient: transientpath (no Russian roulette) into a streakhdrfilm, whose time
// filter <rfilter name="tfilter"> is read but never applied (a histogram), under the film's
// older parameter names and the newer ones.
TEST(PeerTransient, Mitsuba2TransientpathAndStreakhdrfilm) {
    const std::string integrator = "<integrator type=\"transientpath\">" +
                                   param("integer", "max_depth", "4") +
                                   param("integer", "rr_depth", "5") + "</integrator>";
    const std::string filters =
        "<rfilter name=\"rfilter\" type=\"box\"/>"
        "<rfilter name=\"tfilter\" type=\"gaussian\"><float name=\"stddev\" value=\"2\"/>"
        "</rfilter>";
    const std::string size = param("integer", "width", "16") + param("integer", "height", "12");
    const std::string old_names = "<film type=\"streakhdrfilm\">" + size +
                                  param("integer", "time", "40") +
                                  param("float", "exposure_time", "0.1") +
                                  param("float", "time_offset", "2") + filters + "</film>";
    // The peer's sensor takes its film whatever its name.
    const std::string new_names = "<film type=\"streakhdrfilm\" name=\"streakfilm\">" + size +
                                  param("integer", "num_bins", "40") +
                                  param("float", "bin_width_opl", "0.1") +
                                  param("float", "start_opl", "2") +
                                  param("string", "pixel_format", "rgba") + filters + "</film>";
    const Cube native =
        render(scene("3.0.0", native_path(4, 0), native_film(40, 0.1, 2.0, kHistogram)), "native");
    expect_same_cube(render(scene("2.0.0", integrator, old_names), "m2-old"), native);
    expect_same_cube(render(scene("2.0.0", integrator, new_names), "m2-new"), native);

    // Mitsuba 2's defaults: 1000 bins of 1 from 0, max_depth -1; no roulette.
    auto loaded = load_scene_string(scene("2.0.0", "<integrator type=\"transientpath\"/>",
                                          "<film type=\"streakhdrfilm\">" + size + "</film>"),
                                    {}, ".");
    const auto& integ = dynamic_cast<const MonteCarloIntegrator&>(loaded->integrator());
    EXPECT_EQ(integ.max_depth(), -1);
    EXPECT_EQ(integ.rr_depth(), 0);
    const auto& film = dynamic_cast<const TimeResolvedFilm&>(loaded->sensor().film());
    EXPECT_EQ(film.grid().bins, 1000);
    EXPECT_EQ(film.grid().bin_width, 1.0);
    EXPECT_EQ(film.grid().start, 0.0);
}

// A femto scene's transient_path is femto's: mitransient's parameters are unknown to it unless
// the scene is mitransient's (its film says so).
TEST(PeerTransient, FemtoScenesAreLeftAlone) {
    const std::string xml =
        scene("3.0.0", mitransient_path(param("boolean", "camera_unwarp", "true")),
              native_film(40, 0.1, 2.0, kHistogram));
    expect_error_at(xml, "camera_unwarp", "has no parameter \"camera_unwarp\"");
}

// Bad values are errors at the element that holds them, under the peer's names.
TEST(PeerTransient, MitransientErrorsAreLocated) {
    const std::string path = mitransient_path("");
    auto film = [&](const std::string& time) {
        return scene("3.0.0", path, mitransient_film(time));
    };
    expect_error_at(film(mitransient_time(-3, 0.1, 2.0)), "temporal_bins",
                    "temporal_bins must be >= 1");
    expect_error_at(film(param("float", "start_opl", "nan")), "start_opl",
                    "\"start_opl\" must be a finite number");
    expect_error_at(film(param("float", "bin_width_opl", "0")), "bin_width_opl",
                    "bin_width_opl must be > 0");
    expect_error_at(film(param("float", "temporal_bins", "40")), "temporal_bins",
                    "\"temporal_bins\" must be an <integer>");
    expect_error_at(film(param("float", "bin_width_ops", "0.1")), "bin_width_ops",
                    "has no parameter \"bin_width_ops\" (did you mean \"bin_width_opl\"?)");
    expect_error_at(film(param("string", "pixel_format", "rgb")), "pixel_format",
                    "<film type=\"transient_hdr_film\"> (mitransient) has no parameter");
    expect_error_at(film(param("integer", "crop_width", "8")), "crop_width",
                    "crop windows are not supported");
    // Under --lenient a parameter mitransient does not know is a warning, as femto's own are.
    LoadOptions lenient;
    lenient.lenient = true;
    EXPECT_NO_THROW(load_scene_string(film(param("string", "pixel_format", "rgb")), lenient, "."));

    auto integ = [&](const std::string& params) {
        return scene("3.0.0", mitransient_path(params), mitransient_film(""));
    };
    expect_error_at(integ(param("integer", "rr_depth", "0")), "rr_depth", "rr_depth must be > 0");
    expect_error_at(integ(param("integer", "max_depth", "-2")), "max_depth",
                    "max_depth must be -1");
    expect_error_at(integ(param("boolean", "discard_direct_light", "true")), "discard_direct_light",
                    "not supported");
    expect_error_at(integ(param("string", "temporal_filter", "tent")), "temporal_filter",
                    "must be one of");
    expect_error_at(integ(param("float", "gaussian_stddev", "-1")), "gaussian_stddev",
                    "gaussian_stddev must be > 0");
    expect_error_at(integ(param("boolean", "camera_unwrap", "true")), "camera_unwrap",
                    "did you mean \"camera_unwarp\"?");
    // mitransient's volumetric integrator needs its film.
    expect_error_at(scene("3.0.0", "<integrator type=\"transient_prbvolpath\"/>",
                          native_film(40, 0.1, 2.0, kHistogram)),
                    "transient_prbvolpath", "renders into a transient_hdr_film");
    expect_error_at(
        scene("3.0.0", "<integrator type=\"transient_nlos_path\"/>", mitransient_film("")),
        "transient_nlos_path", "has no femto counterpart");
}

TEST(PeerTransient, Mitsuba2ErrorsAreLocated) {
    const std::string integrator = "<integrator type=\"transientpath\"/>";
    auto film = [&](const std::string& body) {
        return scene("2.0.0", integrator,
                     "<film type=\"streakhdrfilm\">\n" + param("integer", "width", "8") +
                         param("integer", "height", "8") + body +
                         "\n<rfilter name=\"rfilter\" "
                         "type=\"box\"/>\n</film>");
    };
    expect_error_at(film(param("integer", "num_bins", "-1")), "num_bins", "num_bins must be >= 1");
    expect_error_at(film(param("float", "exposure_time", "nan")), "exposure_time",
                    "must be a finite number");
    expect_error_at(
        film(param("integer", "time", "10") + "\n" + param("integer", "num_bins", "10")),
        "num_bins", "give num_bins or time, not both");
    expect_error_at(film(param("string", "pixel_format", "luminance")), "pixel_format",
                    "femto writes RGB");
    expect_error_at(film(param("float", "bins", "10")), "\"bins\"",
                    "<film type=\"streakhdrfilm\"> (mitsuba2-transient) has no parameter \"bins\"");
    expect_error_at(film("<rfilter type=\"gaussian\"/>"), "<rfilter type=\"gaussian\"/>",
                    "left unnamed");
    // The time filter is built to check it, although never applied.
    expect_error_at(film("<rfilter name=\"tfilter\" type=\"gaussian\">\n" +
                         param("float", "stdev", "2") + "</rfilter>"),
                    "stdev", "\"stdev\"");
    auto integ = [&](const std::string& params) {
        return scene("2.0.0", "<integrator type=\"transientpath\">\n" + params + "\n</integrator>",
                     "<film type=\"streakhdrfilm\">" + param("integer", "width", "8") +
                         param("integer", "height", "8") + "</film>");
    };
    expect_error_at(integ(param("integer", "rr_depth", "0")), "rr_depth", "rr_depth must be > 0");
    expect_error_at(integ(param("boolean", "discard_direct_paths", "true")), "discard_direct_paths",
                    "not supported");
    expect_error_at(integ(param("integer", "maxdepth", "3")), "maxdepth",
                    "did you mean \"max_depth\"?");
    expect_error_at(scene("2.0.0", integrator, native_film(40, 0.1, 2.0, kHistogram)),
                    "transientpath", "renders into a streakhdrfilm");
}
