// Spectra in scene files: the CIE tables against published values, the conversion to RGB
// (Mitsuba 3's method, docs/compatibility.md) and the <spectrum>/<blackbody> tags.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "color/spectrum.h"
#include "femto/bsdf.h"
#include "femto/sensor.h"
#include "scene/spectrum_tags.h"
#include "scene_util.h"

using namespace femto;
using femto::test::load_error;
using femto::test::scene_xml;
namespace sp = femto::spectrum;

namespace {

std::array<double, 2> chromaticity(const std::array<double, 3>& xyz) {
    const double s = xyz[0] + xyz[1] + xyz[2];
    return {xyz[0] / s, xyz[1] / s};
}

sp::Conversion flat(double v, sp::Use use) {
    return sp::convert([v](double) { return v; }, sp::kMinNm, sp::kMaxNm, use);
}

}  // namespace

TEST(SpectrumCie, TableMatchesPublishedValues) {
    // CIE 1931 2-degree observer (CIE 015:2004, table T.4).
    struct Row {
        double nm, x, y, z;
    };
    for (const Row& r : {Row{450, 0.3362, 0.0380, 1.7721}, Row{500, 0.0049, 0.3230, 0.2720},
                         Row{555, 0.5121, 1.0000, 0.0057}, Row{600, 1.0622, 0.6310, 0.0008}}) {
        const auto c = sp::cie1931_xyz(r.nm);
        EXPECT_NEAR(c[0], r.x, 1e-4) << r.nm;
        EXPECT_NEAR(c[1], r.y, 1e-4) << r.nm;
        EXPECT_NEAR(c[2], r.z, 1e-4) << r.nm;
    }
    // Linear between the 5 nm samples, zero outside 360..830 nm.
    const auto mid = sp::cie1931_xyz(557.5);
    EXPECT_NEAR(mid[1], (1.0 + 0.995) / 2, 1e-12);
    EXPECT_EQ(sp::cie1931_xyz(359.9)[2], 0.0);
    EXPECT_EQ(sp::cie1931_xyz(830.1)[0], 0.0);
    EXPECT_GT(sp::cie1931_xyz(830)[0], 0.0);
    EXPECT_NEAR(sp::cie_d65(560), 1.0, 1e-12);  // D65 is relative to 560 nm
}

TEST(SpectrumCie, IntegralOfYBarAndWhitePoints) {
    double y_integral = 0;  // 1 nm steps, trapezoid
    for (int nm = 360; nm < 830; ++nm)
        y_integral += 0.5 * (sp::cie1931_xyz(nm)[1] + sp::cie1931_xyz(nm + 1)[1]);
    EXPECT_NEAR(y_integral, 106.857, 2e-3);

    // A perfect white reflector under D65 has D65's white point, x = 0.3127, y = 0.3290,
    // and the luminance Mitsuba 3's normalisation gives it (0.99889: see spectrum.cpp).
    const auto white = flat(1, sp::Use::Reflectance);
    EXPECT_NEAR(chromaticity(white.xyz)[0], 0.3127, 2e-4);
    EXPECT_NEAR(chromaticity(white.xyz)[1], 0.3290, 2e-4);
    EXPECT_NEAR(white.xyz[1], 0.99889, 1e-5);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(white.rgb[k], 0.9989, 2e-4) << k;
    // The equal-energy spectrum (illuminant E) sits at x = y = 1/3, with luminance 1.
    const auto e = flat(1, sp::Use::Emission);
    EXPECT_NEAR(chromaticity(e.xyz)[0], 1 / 3.0, 1e-4);
    EXPECT_NEAR(chromaticity(e.xyz)[1], 1 / 3.0, 1e-4);
    EXPECT_NEAR(e.xyz[1], 1.0, 1e-5);
}

TEST(SpectrumCie, MatrixMapsD65ToWhite) {
    // D65's tristimulus values at Y = 1 (CIE 015:2004): 0.95047, 1, 1.08883.
    const auto rgb = sp::xyz_to_linear_srgb({0.95047, 1.0, 1.08883});
    for (double c : rgb) EXPECT_NEAR(c, 1.0, 1e-3);
}

TEST(SpectrumConversion, ReflectanceEmissionAndClamping) {
    // A constant reflectance stays grey; a constant emission is Mitsuba 3's equal-energy
    // colour, M (1, 1, 1), the same as the flat sampled emission spectrum.
    EXPECT_EQ(sp::convert_uniform(0.5, sp::Use::Reflectance), Color(0.5f));
    const Color e = sp::convert_uniform(2, sp::Use::Emission);
    EXPECT_NEAR(e.r, 2 * 1.204794, 1e-6);
    EXPECT_NEAR(e.g, 2 * 0.948291, 1e-6);
    EXPECT_NEAR(e.b, 2 * 0.908916, 1e-6);
    const auto flat_emission = flat(2, sp::Use::Emission);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(flat_emission.rgb[k], e[k], 2e-3 * e[k]) << k;

    // The conversion is linear below the clamp.
    const auto half = flat(0.5, sp::Use::Reflectance);
    for (int k = 0; k < 3; ++k)
        EXPECT_FLOAT_EQ(half.rgb[k], 0.5f * flat(1, sp::Use::Reflectance).rgb[k]);

    // A narrow red line is outside sRGB: a reflectance is clamped to [0, 1], an emission only
    // below 0, an unbounded quantity (eta, k) too.
    const std::vector<double> nm = {600, 610, 620}, v = {0, 40, 0};
    const auto r = sp::convert_sampled(nm, v, sp::Use::Reflectance);
    EXPECT_TRUE(r.clamped);
    EXPECT_EQ(r.rgb.r, 1.0f);
    EXPECT_EQ(r.rgb.b, 0.0f);
    const auto em = sp::convert_sampled(nm, v, sp::Use::Emission);
    EXPECT_TRUE(em.clamped);
    EXPECT_GT(em.rgb.r, 1.0f);
    EXPECT_EQ(em.rgb.b, 0.0f);
    const auto un = sp::convert_sampled(nm, v, sp::Use::Unbounded);
    EXPECT_GT(un.rgb.r, 1.0f);
    EXPECT_FALSE(flat(0.5, sp::Use::Reflectance).clamped);

    // Outside its samples a spectrum is zero (Mitsuba 3 does not extend it).
    const auto part = sp::convert_sampled({500, 600}, {1, 1}, sp::Use::Emission);
    const auto full = sp::convert_sampled({360, 830}, {1, 1}, sp::Use::Emission);
    EXPECT_LT(part.xyz[1], 0.8 * full.xyz[1]);
    EXPECT_GT(part.xyz[1], 0.5 * full.xyz[1]);
}

TEST(SpectrumConversion, SampledProblems) {
    EXPECT_EQ(sp::sampled_problem({400, 500}, {0.1, 0.2}), "");
    EXPECT_NE(sp::sampled_problem({400}, {0.1}).find("at least two"), std::string::npos);
    EXPECT_NE(sp::sampled_problem({500, 400}, {0.1, 0.2}).find("must increase"), std::string::npos);
    EXPECT_NE(sp::sampled_problem({400, 400}, {0.1, 0.2}).find("must increase"), std::string::npos);
    EXPECT_NE(sp::sampled_problem({-400, 500}, {0.1, 0.2}).find("not positive"), std::string::npos);
    EXPECT_NE(sp::sampled_problem({400, 500}, {NAN, 0.2}).find("not finite"), std::string::npos);
}

TEST(SpectrumBlackbody, PlanckLaw) {
    // Wien's displacement law: the peak is at 2.897771955e6 nm K / T.
    const double t = 5000, peak = 2.897771955e6 / t;
    EXPECT_GT(sp::planck(peak, t), sp::planck(peak - 1, t));
    EXPECT_GT(sp::planck(peak, t), sp::planck(peak + 1, t));
    // Stefan-Boltzmann: the radiance integrates to sigma T^4 / pi.
    double total = 0;
    for (double nm = 50; nm < 200000; nm += 0.5) total += 0.5 * sp::planck(nm + 0.25, t);
    const double sigma = 5.670374419e-8;
    EXPECT_NEAR(total / (sigma * std::pow(t, 4) / M_PI), 1.0, 1e-4);
    // CIE illuminant A is a black body at 2856 K: x = 0.44757, y = 0.40745; the Planckian
    // locus at 6500 K is at (0.3135, 0.3236).
    auto xy = [](double kelvin) {
        return chromaticity(sp::convert([&](double nm) { return sp::planck(nm, kelvin); },
                                        sp::kMinNm, sp::kMaxNm, sp::Use::Emission)
                                .xyz);
    };
    EXPECT_NEAR(xy(2856)[0], 0.44757, 3e-4);
    EXPECT_NEAR(xy(2856)[1], 0.40745, 3e-4);
    EXPECT_NEAR(xy(6500)[0], 0.3135, 2e-4);
    EXPECT_NEAR(xy(6500)[1], 0.3236, 2e-4);
}

namespace {

std::vector<float> render_image(Scene& scene) {
    RenderOptions opt;
    opt.seed = 7;
    opt.spp = 4;
    render(scene, opt);
    return scene.sensor().film().steady_image();
}

// A diffuse square lit by a point light; the two values are XML property elements.
std::string lit_square(const std::string& reflectance, const std::string& intensity) {
    return scene_xml(
        "<integrator type=\"path\"/>"
        "<sensor type=\"perspective\"><transform name=\"to_world\"><lookat origin=\"0, 0, 3\" "
        "target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform><film type=\"hdrfilm\"><integer "
        "name=\"width\" value=\"8\"/><integer name=\"height\" value=\"8\"/></film></sensor>"
        "<shape type=\"rectangle\"><bsdf type=\"diffuse\">" +
        reflectance +
        "</bsdf></shape>"
        "<emitter type=\"point\"><point name=\"position\" value=\"0, 0, 2\"/>" +
        intensity + "</emitter>");
}

std::string rgb_element(const std::string& name, const Color& c) {
    // Nine significant digits give back the same float.
    char value[128];
    std::snprintf(value, sizeof value, "%.9g, %.9g, %.9g", c.r, c.g, c.b);
    return "<rgb name=\"" + name + "\" value=\"" + value + "\"/>";
}

}  // namespace

TEST(SpectrumLoader, UseFollowsTheObjectAndTheName) {
    EXPECT_EQ(detail::spectrum_use("emitter", "radiance"), sp::Use::Emission);
    EXPECT_EQ(detail::spectrum_use("emitter", "intensity"), sp::Use::Emission);
    EXPECT_EQ(detail::spectrum_use("bsdf", "reflectance"), sp::Use::Reflectance);
    EXPECT_EQ(detail::spectrum_use("bsdf", "eta"), sp::Use::Unbounded);
    EXPECT_EQ(detail::spectrum_use("medium", "sigma_t"), sp::Use::Unbounded);
}

TEST(SpectrumLoader, SampledSpectraRenderAsTheirRgb) {
    const std::string pairs = "400:0.2, 500:0.5 600:0.7,700:0.4";  // commas or spaces
    const std::vector<double> nm = {400, 500, 600, 700}, v = {0.2, 0.5, 0.7, 0.4};
    const Color refl = sp::convert_sampled(nm, v, sp::Use::Reflectance).rgb;
    const Color emit = sp::convert_sampled(nm, v, sp::Use::Emission).rgb;
    ASSERT_GT(refl.r, refl.b);  // a reddish spectrum
    auto spectral =
        load_scene_string(lit_square("<spectrum name=\"reflectance\" value=\"" + pairs + "\"/>",
                                     "<spectrum name=\"intensity\" value=\"" + pairs + "\"/>"));
    auto rgb = load_scene_string(
        lit_square(rgb_element("reflectance", refl), rgb_element("intensity", emit)));
    const auto a = render_image(*spectral), b = render_image(*rgb);
    ASSERT_EQ(a.size(), b.size());
    double sum = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i], b[i]) << i;
        sum += a[i];
    }
    EXPECT_GT(sum, 0);
}

TEST(SpectrumLoader, ConstantSpectrumIsGreyForReflectances) {
    auto spectral =
        load_scene_string(lit_square("<spectrum name=\"reflectance\" value=\"0.5\"/>", ""));
    auto rgb = load_scene_string(lit_square("<rgb name=\"reflectance\" value=\"0.5\"/>", ""));
    EXPECT_EQ(render_image(*spectral), render_image(*rgb));
    // In an emitter it is Mitsuba 3's equal-energy colour, not grey.
    auto emit = load_scene_string(lit_square("", "<spectrum name=\"intensity\" value=\"1\"/>"));
    auto emit_rgb = load_scene_string(
        lit_square("", rgb_element("intensity", sp::convert_uniform(1, sp::Use::Emission))));
    EXPECT_EQ(render_image(*emit), render_image(*emit_rgb));
}

TEST(SpectrumLoader, SpectrumFiles) {
    const auto dir = femto::testing::temp_dir("spectrum-files");
    femto::test::write_text(dir / "red.spd",
                            "# Mitsuba 0.6 spectrum\n400 0.2\n500 0.5\r\n\n600 0.7  # peak\n"
                            "700 0.4\n");
    auto from_file = load_scene_string(
        lit_square("<spectrum name=\"reflectance\" filename=\"red.spd\"/>", ""), {}, dir.string());
    auto inline_pairs = load_scene_string(lit_square(
        "<spectrum name=\"reflectance\" value=\"400:0.2 500:0.5 600:0.7 700:0.4\"/>", ""));
    EXPECT_EQ(render_image(*from_file), render_image(*inline_pairs));

    femto::test::write_text(dir / "bad.spd", "400 0.2\n500 0.5\n600 zero\n");
    std::string msg = load_error(
        lit_square("<spectrum name=\"reflectance\" filename=\"bad.spd\"/>", ""), {}, dir.string());
    EXPECT_NE(msg.find("bad.spd:3:1: expected \"wavelength value\""), std::string::npos) << msg;
    femto::test::write_text(dir / "one.spd", "400 0.2\n");
    msg = load_error(lit_square("<spectrum name=\"reflectance\" filename=\"one.spd\"/>", ""), {},
                     dir.string());
    EXPECT_NE(msg.find("at least two"), std::string::npos) << msg;
    msg = load_error(lit_square("<spectrum name=\"reflectance\" filename=\"none.spd\"/>", ""), {},
                     dir.string());
    EXPECT_NE(msg.find("spectrum file \"none.spd\" not found (searched: "), std::string::npos)
        << msg;
    std::filesystem::remove_all(dir);
}

TEST(SpectrumLoader, Blackbody) {
    // Mitsuba 0.6's <blackbody>: Planck's law in W m^-2 sr^-1 nm^-1, times `scale`.
    const double scale = 1e-4;
    const Color expected = sp::convert([&](double nm) { return scale * sp::planck(nm, 5000); },
                                       sp::kMinNm, sp::kMaxNm, sp::Use::Emission)
                               .rgb;
    ASSERT_GT(expected.r, expected.b);  // 5000 K is warm
    auto bb = load_scene_string(
        lit_square("", "<blackbody name=\"intensity\" temperature=\"5000K\" scale=\"1e-4\"/>"), {});
    auto rgb = load_scene_string(lit_square("", rgb_element("intensity", expected)));
    EXPECT_EQ(render_image(*bb), render_image(*rgb));
    auto in_06 = scene_xml(
        "<shape type=\"rectangle\"><emitter type=\"area\"><blackbody name=\"radiance\" "
        "temperature=\"6500\"/></emitter></shape>",
        "0.6.0");
    EXPECT_NO_THROW(load_scene_string(in_06));
}

TEST(SpectrumLoader, BadSpectraAreLocatedErrors) {
    auto refl = [](const std::string& element) {
        return load_error(scene_xml("<shape type=\"rectangle\"><bsdf type=\"diffuse\">\n" +
                                    element + "</bsdf></shape>"));
    };
    struct Case {
        std::string element, expected;
    };
    const std::vector<Case> cases = {
        {"<spectrum name=\"reflectance\" value=\"400:0.5\"/>", "at least two"},
        {"<spectrum name=\"reflectance\" value=\"500:0.5, 400:0.6\"/>", "must increase"},
        {"<spectrum name=\"reflectance\" value=\"-400:0.5, 400:0.6\"/>", "not positive"},
        {"<spectrum name=\"reflectance\" value=\"400:nan, 500:0.6\"/>", "not finite"},
        {"<spectrum name=\"reflectance\" value=\"400:abc, 500:0.6\"/>",
         "\"400:abc\" is not a wavelength:value pair"},
        {"<spectrum name=\"reflectance\" value=\"400:0.5, 500\"/>",
         "\"500\" is not a wavelength:value pair"},
        {"<spectrum name=\"reflectance\" value=\"\"/>", "value is empty"},
        {"<spectrum name=\"reflectance\" value=\"nan\"/>", "not a finite number"},
        {"<spectrum name=\"reflectance\" value=\"0.1 0.2 0.3\"/>", "use <rgb>"},
        {"<spectrum name=\"reflectance\"/>", "either a \"value\" or a \"filename\""},
        {"<spectrum name=\"reflectance\" value=\"0.5\" intent=\"x\"/>",
         "unknown attribute \"intent\""},
        {"<spectrum type=\"blackbody\" name=\"reflectance\"><float name=\"temperature\" "
         "value=\"5000\"/></spectrum>",
         "<spectrum type=\"blackbody\"> is not supported"},
        {"<blackbody name=\"reflectance\" temperature=\"-5K\"/>", "must be positive"},
        {"<blackbody name=\"reflectance\" temperature=\"hot\"/>", "\"hot\" is not a finite"},
        {"<blackbody name=\"reflectance\"/>", "needs the attribute \"temperature\""},
    };
    for (const Case& c : cases) {
        const std::string msg = refl(c.element);
        EXPECT_NE(msg.find(c.expected), std::string::npos) << c.element << "\n" << msg;
        EXPECT_EQ(msg.rfind("<string>:4:", 0), 0u) << c.element << "\n" << msg;
    }
}
