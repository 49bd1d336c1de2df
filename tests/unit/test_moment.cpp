// The `moment` integrator and the AOV channels it writes: its first moment is the nested
// integrator's image (same seed, same random numbers), its second moment gives the per-sample
// variance of a scene whose sample distribution is known, the EXR holds Mitsuba 3's channel
// names (read back with OpenImageIO), and what it cannot do is refused with a location.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "femto/error.h"
#include "femto/host.h"
#include "femto/testing/render.h"

namespace {

using femto::testing::MeanAndError;

constexpr int kRes = 8;

// An emitting plane (radiance `le`, grey) seen from above at height 5 by an orthographic
// camera (kRes^2 pixels, box filter) through a mask of opacity 0.3 over an unlit diffuse
// material: a path tracer's camera sample is `le` with probability 0.7 and 0 otherwise.
std::string mask_scene(const std::string& integrator, int spp, double le,
                       const std::string& film = "") {
    const std::string res = std::to_string(kRes);
    const std::string f = film.empty() ? "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" +
                                             res + "\"/><integer name=\"height\" value=\"" + res +
                                             "\"/><rfilter type=\"box\"/></film>"
                                       : film;
    return "<scene version=\"3.0.0\">\n" + integrator +
           "\n<sensor type=\"orthographic\"><transform name=\"to_world\"><lookat "
           "origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/></transform><sampler "
           "type=\"independent\"><integer name=\"sample_count\" value=\"" +
           std::to_string(spp) + "\"/></sampler>" + f +
           "</sensor><shape type=\"rectangle\"><transform name=\"to_world\"><scale "
           "value=\"3\"/></transform><bsdf type=\"diffuse\"><float name=\"reflectance\" "
           "value=\"0\"/></bsdf><emitter type=\"area\"><float name=\"radiance\" value=\"" +
           std::to_string(le) +
           "\"/></emitter></shape><shape type=\"rectangle\"><transform name=\"to_world\"><scale "
           "value=\"3\"/><translate z=\"2.5\"/></transform><bsdf type=\"mask\"><float "
           "name=\"opacity\" value=\"0.3\"/><bsdf type=\"diffuse\"/></bsdf></shape></scene>";
}

const char* kPath = "<integer name=\"max_depth\" value=\"4\"/>";

std::string moment_of(const std::string& nested) {
    return "<integrator type=\"moment\">" + nested + "</integrator>";
}

// Renders `xml` with `seed`, writes its outputs and reads every channel of OUTBASE.exr back
// with OpenImageIO: name -> [pixel] values.
std::map<std::string, std::vector<float>> render_exr(const std::string& xml, uint64_t seed,
                                                     const std::string& name) {
    auto scene = femto::load_scene_string(xml);
    femto::RenderOptions opt;
    opt.seed = seed;
    const femto::RenderStats stats = femto::render(*scene, opt);
    const auto dir = femto::testing::temp_dir("moment-" + name);
    const std::string base = (dir / name).string();
    scene->sensor().film().write(base, femto::make_render_info(*scene, opt, stats));
    auto in = OIIO::ImageInput::open(base + ".exr");
    EXPECT_TRUE(in);
    std::map<std::string, std::vector<float>> channels;
    if (!in) return channels;
    const OIIO::ImageSpec spec = in->spec();
    std::vector<float> all(size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels));
    EXPECT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()));
    for (int c = 0; c < spec.nchannels; ++c) {
        std::vector<float>& v = channels[spec.channelnames[size_t(c)]];
        for (size_t p = 0; p < all.size() / size_t(spec.nchannels); ++p)
            v.push_back(all[p * size_t(spec.nchannels) + size_t(c)]);
    }
    in->close();
    std::filesystem::remove_all(dir);
    return channels;
}

// Linear Rec.709 RGB to CIE XYZ (double precision reference).
std::array<double, 3> xyz(double r, double g, double b) {
    return {0.412453 * r + 0.357580 * g + 0.180423 * b, 0.212671 * r + 0.715160 * g + 0.072169 * b,
            0.019334 * r + 0.119193 * g + 0.950227 * b};
}

// The EXR holds R, G, B and Mitsuba 3's channels for each nested integrator (named or not, in
// order): NAME.X/Y/Z and m2_NAME.X/Y/Z.
TEST(MomentIntegrator, ExrChannelNamesAreMitsubas) {
    const auto ch =
        render_exr(mask_scene(moment_of(std::string("<integrator type=\"path\" name=\"pt\">") +
                                        kPath + "</integrator><integrator type=\"direct\"/>"),
                              4, 1.0),
                   1, "names");
    std::vector<std::string> names;
    for (const auto& [n, v] : ch) names.push_back(n);
    // (unnamed children are numbered among themselves: the direct integrator is _arg_0)
    const std::vector<std::string> expected = {
        "B",        "G",           "R",           "_arg_0.X",    "_arg_0.Y",
        "_arg_0.Z", "m2__arg_0.X", "m2__arg_0.Y", "m2__arg_0.Z", "m2_pt.X",
        "m2_pt.Y",  "m2_pt.Z",     "pt.X",        "pt.Y",        "pt.Z"};
    std::vector<std::string> sorted = expected;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(names, sorted);
}

// The image and the first moment are the nested integrator's own image (the first nested
// integrator draws the sample's random numbers as it does alone): equal up to float rounding
// of the XYZ conversion (1e-5 relative).
TEST(MomentIntegrator, FirstMomentIsTheNestedImage) {
    const std::string path = std::string("<integrator type=\"path\">") + kPath + "</integrator>";
    const auto alone = render_exr(mask_scene(path, 16, 1.0), 7, "alone");
    const auto moment = render_exr(mask_scene(moment_of(path), 16, 1.0), 7, "moment");
    ASSERT_EQ(moment.count("_arg_0.Y"), 1u);
    double total = 0;
    for (size_t p = 0; p < alone.at("R").size(); ++p) {
        for (const char* c : {"R", "G", "B"}) EXPECT_EQ(moment.at(c)[p], alone.at(c)[p]) << p;
        const auto e = xyz(alone.at("R")[p], alone.at("G")[p], alone.at("B")[p]);
        const char* axes[] = {"_arg_0.X", "_arg_0.Y", "_arg_0.Z"};
        for (int a = 0; a < 3; ++a)
            EXPECT_NEAR(moment.at(axes[a])[p], e[size_t(a)], 1e-5 * e[size_t(a)] + 1e-7) << p;
        total += e[1];
    }
    EXPECT_GT(total, 0);
}

// Each camera sample is Y = 2 with probability p = 0.7 (through the mask) and 0 otherwise.
// Over n samples a pixel's m1 = 2 k / n and m2 = 4 k / n, k ~ Binomial(n, p): E[m2] = 4 p and
// E[m2 - m1^2] = 4 p (1 - p) (1 - 1/n), the per-sample variance up to the 1/n bias of the
// plain second moment. The pixels are independent: their means are compared within 4 standard
// errors of their spread. X and Z are Y times the white point's x, z (0.950456, 1.088754).
TEST(MomentIntegrator, SecondMomentGivesTheSampleVariance) {
    const int spp = 128;
    const double p = 0.7, le = 2.0;
    const auto ch = render_exr(
        mask_scene(moment_of(std::string("<integrator type=\"path\">") + kPath + "</integrator>"),
                   spp, le),
        3, "variance");
    std::vector<double> m2, var;
    for (size_t i = 0; i < ch.at("_arg_0.Y").size(); ++i) {
        const double m1 = ch.at("_arg_0.Y")[i], s = ch.at("m2__arg_0.Y")[i];
        m2.push_back(s);
        var.push_back(s - m1 * m1);
        // The sample values are 0 and 2 only: m2 = 2 m1 exactly (up to rounding), and X, Z
        // follow Y.
        EXPECT_NEAR(s, le * m1, 1e-5 * s + 1e-7);
        EXPECT_NEAR(ch.at("m2__arg_0.X")[i], s * 0.950456 * 0.950456, 1e-4 * s + 1e-7);
        EXPECT_NEAR(ch.at("m2__arg_0.Z")[i], s * 1.088754 * 1.088754, 1e-4 * s + 1e-7);
    }
    const MeanAndError a = femto::testing::mean_and_error(m2);
    const MeanAndError b = femto::testing::mean_and_error(var);
    const double var_expected = le * le * p * (1 - p) * (1 - 1.0 / spp);
    std::printf(
        "[moment] m2 %.4f +- %.4f (expected %.4f); m2 - m1^2 %.4f +- %.4f (expected %.4f)\n",
        a.mean, a.standard_error, le * le * p, b.mean, b.standard_error, var_expected);
    EXPECT_NEAR(a.mean, le * le * p, 4 * a.standard_error);
    EXPECT_NEAR(b.mean, var_expected, 4 * b.standard_error);
}

std::string render_error(const std::string& xml) {
    try {
        auto scene = femto::load_scene_string(xml);
        femto::render(*scene, femto::RenderOptions{});
    } catch (const femto::SceneError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected a SceneError";
    return {};
}

// Moments are steady (as Mitsuba 3's): a transient film refuses the AOVs, located at the
// integrator. A light tracer inside, or no integrator inside, is refused at load.
TEST(MomentIntegrator, RefusesTransientFilmsLightTracersAndNothingNested) {
    const std::string film =
        "<film type=\"transient\"><integer name=\"width\" value=\"8\"/><integer name=\"height\" "
        "value=\"8\"/><float name=\"start\" value=\"4\"/><float name=\"bin_width\" "
        "value=\"0.1\"/><integer name=\"bins\" value=\"20\"/></film>";
    const std::string transient = render_error(mask_scene(
        moment_of(std::string("<integrator type=\"transient_path\">") + kPath + "</integrator>"), 1,
        1.0, film));
    EXPECT_NE(transient.find("does not record"), std::string::npos) << transient;
    EXPECT_NE(transient.find("hdrfilm"), std::string::npos) << transient;
    EXPECT_NE(transient.find("<string>:2:"), std::string::npos) << transient;
    const std::string light =
        render_error(mask_scene(moment_of("<integrator type=\"transient_light\"/>"), 1, 1.0));
    EXPECT_NE(light.find("cannot nest the transient_light"), std::string::npos) << light;
    const std::string none = render_error(mask_scene(moment_of(""), 1, 1.0));
    EXPECT_NE(none.find("at least one nested"), std::string::npos) << none;
}

}  // namespace
