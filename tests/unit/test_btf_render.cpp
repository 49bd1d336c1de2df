// The `btf` material in full renders: a BTF is not reciprocal (BTF A's G_1 = (l.a)(v.b) with
// a != b), so the light tracer and BDPT, which evaluate it from the lights' side, must agree with
// the path tracer only if they evaluate it with the camera's side as the view (eval_adjoint()).
// And a transient render of it integrates to the steady one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "agreement_util.h"
#include "btf/synth.h"
#include "btf_test_util.h"
#include "cube_util.h"
#include "femto/direction_mesh.h"
#include "scene_util.h"

namespace {

using namespace femto;
using namespace femto::test;

constexpr double kPiD = 3.14159265358979323846;

std::string btf_file() { return write_btf(small_btf_a(), "btf-render", "a.dfmf"); }

// A BTF square of side 4 (uv_scale 2: the texture twice across) under a point light off to one
// side, seen from above at an angle by a 16 x 16 pinhole camera; one bounce.
std::string btf_scene(const std::string& integrator, const std::string& file,
                      const std::string& extra = "") {
    return "<scene version=\"3.0.0\"><default name=\"spp\" value=\"4\"/>"
           "<integrator type=\"" +
           integrator + "\"><integer name=\"max_depth\" value=\"2\"/>" + extra +
           "</integrator>"
           "<sensor type=\"perspective\"><float name=\"fov\" value=\"50\"/>"
           "<transform name=\"to_world\"><lookat origin=\"1.5, -2, 4\" target=\"0, 0, 0\" "
           "up=\"0, 0, 1\"/></transform>" +
           "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"$spp\"/>"
           "</sampler>" +
           box_transient_film(16, 16, 3.0, 0.25, 24) +
           "</sensor><emitter type=\"point\"><point name=\"position\" x=\"-1.2\" y=\"0.8\" "
           "z=\"1.6\"/><rgb name=\"intensity\" value=\"6\"/></emitter>"
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2\"/>"
           "</transform><bsdf type=\"btf\"><string name=\"filename\" value=\"" +
           file + "\"/><float name=\"uv_scale\" value=\"2\"/></bsdf></shape></scene>";
}

void expect_agrees_with_path_tracer(const std::string& integrator, int spp,
                                    const std::string& extra = "") {
    constexpr int kRuns = 16;
    const std::string file = btf_file();
    LoadOptions path_opts, other_opts;
    path_opts.defines = {{"spp", "16"}};
    other_opts.defines = {{"spp", std::to_string(spp)}};
    const auto path =
        render_runs(btf_scene("transient_path", file), path_opts, kRuns, 100, "btf-path");
    const auto other = render_runs(btf_scene(integrator, file, extra), other_opts, kRuns, 200,
                                   "btf-" + integrator);
    expect_agree(cells_of(other, 2, 4, {}), cells_of(path, 2, 4, {}), kRuns, integrator);
}

TEST(BtfRender, LightTracerAgreesWithPathTracer) {
    expect_agrees_with_path_tracer("transient_light", 16);
}

TEST(BtfRender, BdptAgreesWithPathTracer) { expect_agrees_with_path_tracer("transient_bdpt", 4); }

// BDPT's weights favour the light connection (s = 1, t = 2) here, which sees the material from
// the camera's side; its light-tracing strategy (s = 2, t = 1) alone must agree as well.
TEST(BtfRender, BdptLightTracingStrategyAgreesWithPathTracer) {
    expect_agrees_with_path_tracer(
        "transient_bdpt", 16,
        "<integer name=\"strategy_s\" value=\"2\"/><integer name=\"strategy_t\" value=\"1\"/>");
}

}  // namespace

namespace {

// Experiment 1's set-up reduced to its closed form: BTF A (256 x 256 texels) on a plane lit by a
// directional light from a sampled direction, seen from straight above (the view direction
// sample 0) by an orthographic camera with one ray through each pixel's centre (`stratified`
// without jitter). At N x N pixels a pixel covers r = 256 / N texels per side, so the
// prefiltered material takes level log2 r, whose texel under the pixel's centre is exactly the
// box mean of the r x r texels the pixel covers: pixel = E cos(theta_l) / pi x sum_k (box mean
// of T_ck) G_k(l, z), per pixel, at every distance r = 1 ... 256. Again with one jittered
// sample per pixel (`independent`): the lookup is centred on the pixel
// (PixelFootprint::to_pixel_centre), so the same values, within the same tolerance (moving uv
// to the centre rounds it by 2^-24 of uv: 1.5e-5 of a texel of 256; measured 5e-7 relative).
TEST(BtfRender, PrefilteredPlaneMatchesTheClosedFormAtEveryDistance) {
    btf::synth::Options o;
    o.format = btf::Format::Dfmf;
    o.width = o.height = 256;
    o.directions = btf::ubo2003_directions();
    const std::string file = (femto::testing::temp_dir("btf-distance") / "a256.dfmf").string();
    btf::synth::write(file, o);
    const Vec3 light = o.directions[7];  // the 30-degree ring, azimuth 0: (0.5, 0, 0.866)
    ASSERT_NEAR(light.x, 0.5f, 1e-6f);
    const double irradiance = 2.0;
    const btf::synth::HarmonicBtf closed(o.width, o.height);
    for (const bool jittered : {false, true})
        for (const int r : {1, 4, 16, 64, 256}) {
            const int n = 256 / r;
            const std::string sampler =
                jittered ? independent_sampler(1)
                         : "<sampler type=\"stratified\"><integer name=\"sample_count\" "
                           "value=\"1\"/><boolean name=\"jitter\" value=\"false\"/></sampler>";
            const std::string xml =
                "<scene version=\"3.0.0\"><integrator type=\"direct\"/>"
                "<sensor type=\"orthographic\"><transform name=\"to_world\"><lookat origin=\"0, 0, "
                "5\" "
                "target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>" +
                sampler + "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" +
                std::to_string(n) + "\"/><integer name=\"height\" value=\"" + std::to_string(n) +
                "\"/><rfilter type=\"box\"/></film></sensor>"
                "<emitter type=\"directional\"><vector name=\"direction\" x=\"" +
                xml_number(-light.x) + "\" y=\"" + xml_number(-light.y) + "\" z=\"" +
                xml_number(-light.z) + "\"/><rgb name=\"irradiance\" value=\"" +
                xml_number(irradiance) +
                "\"/></emitter><shape type=\"rectangle\"><bsdf type=\"btf\"><string "
                "name=\"filename\" value=\"" +
                file + "\"/><boolean name=\"prefilter\" value=\"true\"/></bsdf></shape></scene>";
            const auto scene = load_scene_string(xml);
            const std::vector<float> image = femto::testing::render_steady(*scene, 1);
            ASSERT_EQ(image.size(), size_t(3 * n * n));
            double worst = 0;
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i)
                    for (int c = 0; c < 3; ++c) {
                        double b = 0;
                        for (int k = 0; k < 3; ++k)
                            b += closed.spatial_box_mean(c, k, uint32_t(i * r), uint32_t(j * r),
                                                         uint32_t(r), uint32_t(r)) *
                                 btf::synth::HarmonicBtf::angular(k, light, Vec3(0, 0, 1));
                        const double want = irradiance * light.z / kPi * b;
                        worst = std::max(worst, std::abs(image[3 * (j * n + i) + c] - want) / want);
                    }
            // Float factors, a float dot product and the renderer's float accumulation: ~1e-6.
            EXPECT_LT(worst, 2e-5) << "r = " << r << (jittered ? ", jittered" : "");
            std::printf("[btf] r = %3d (%3d x %3d pixels%s): worst relative error %.2g\n", r, n, n,
                        jittered ? ", jittered" : "", worst);
        }
}

TEST(BtfRender, AreaLightIsFilteredOverTheConeItSubtends) {
    // Thesis ch. 3's light solid angle, end to end: a prefiltered BTF-A plane lit by a spherical
    // area light (at distance 2, a 40-degree cone, beside the camera's view), seen by an
    // orthographic camera whose one pixel covers 0.002 x 0.002 of the plane's centre (level 0;
    // texel coordinate 3.5, so bilinear weights of 1/4 on texels 3 and 4 in x and y, and linear
    // within the pixel). `direct` takes one light sample per camera sample (uniform in the sphere's
    // visible cone) and the material filters it over PixelFootprint::light_cone = 30 degrees
    // plus half the light direction's turn across the pixel. Expected
    // value and the estimator's variance by quadrature over the cone, with the hierarchy's own
    // rules: barycentric between sampled directions, linear between its 30 and 45-degree entries.
    btf::synth::Options o = small_btf_a();
    o.height = 8;
    const std::string file = write_btf(o, "btf-render", "cone.dfmf");
    const btf::synth::HarmonicBtf closed(o.width, o.height);
    const Vec3 centre(1.5f, 0.f, float(std::sqrt(1.75)));
    const double radius = 2 * std::sin(40 * kPiD / 180), radiance = 3, half_pixel = 0.001;
    constexpr int kSpp = 262144;
    const std::string xml =
        "<scene version=\"3.0.0\"><integrator type=\"direct\"><integer name=\"bsdf_samples\" "
        "value=\"0\"/></integrator><sensor type=\"orthographic\"><transform "
        "name=\"to_world\"><scale x=\"" +
        xml_number(half_pixel) + "\" y=\"" + xml_number(half_pixel) +
        "\"/><lookat origin=\"0, 0, 5\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>" +
        independent_sampler(kSpp) +
        "<film type=\"hdrfilm\"><integer name=\"width\" value=\"1\"/><integer name=\"height\" "
        "value=\"1\"/><rfilter type=\"box\"/></film></sensor><shape type=\"sphere\"><point "
        "name=\"center\" x=\"1.5\" y=\"0\" z=\"" +
        xml_number(centre.z) + "\"/><float name=\"radius\" value=\"" + xml_number(radius) +
        "\"/>"
        "<emitter type=\"area\"><rgb name=\"radiance\" value=\"" +
        xml_number(radiance) +
        "\"/></emitter></shape><shape type=\"rectangle\"><bsdf type=\"btf\"><string "
        "name=\"filename\" value=\"" +
        file + "\"/><boolean name=\"prefilter\" value=\"true\"/></bsdf></shape></scene>";
    const auto scene = load_scene_string(xml);
    const std::vector<float> image = femto::testing::render_steady(*scene, 1);
    ASSERT_EQ(image.size(), 3u);

    const DirectionMesh lights(o.directions), views(o.directions);
    const DirectionMesh::Weights wv = views.interpolate(Vec3(0, 0, 1));
    constexpr double kDeg = kPiD / 180;
    // B(l, v = normal) for channel c with the light filtered over `cone` (radians).
    auto reflectance = [&](int c, const Vec3& l, double cone, bool filtered) {
        const DirectionMesh::Weights wl = lights.interpolate(l);
        const double t = filtered ? std::clamp((cone - 30 * kDeg) / (15 * kDeg), 0.0, 1.0) : 0;
        const double a0 = filtered ? 30 * kDeg : 0, a1 = 45 * kDeg;
        double b = 0;
        for (int k = 0; k < 3; ++k) {
            double s = 0;
            for (const uint32_t x : {3u, 4u})
                for (const uint32_t y : {3u, 4u}) s += 0.25 * closed.spatial(c, k, x, y);
            double g = 0;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    const double w = double(wl.weight[i]) * wv.weight[j];
                    if (w == 0) continue;
                    const Vec3 &dl = o.directions[wl.index[i]], &dv = o.directions[wv.index[j]];
                    using H = btf::synth::HarmonicBtf;
                    g += w * ((1 - t) * H::angular_cap_mean(k, dl, dv, a0, 0) +
                              (t > 0 ? t * H::angular_cap_mean(k, dl, dv, a1, 0) : 0.0));
                }
            b += s * g;
        }
        return b;
    };
    const double D = length(centre), alpha = std::asin(radius / D);
    const double solid_angle = 2 * kPiD * (1 - std::cos(alpha));
    const Frame frame(normalize(centre));
    constexpr int kTheta = 192, kPhi = 384;
    for (int c = 0; c < 3; ++c) {
        double mean = 0, second = 0, unfiltered = 0;
        for (int i = 0; i < kTheta; ++i) {
            const double th = (i + 0.5) * alpha / kTheta;
            for (int j = 0; j < kPhi; ++j) {
                const double ph = (j + 0.5) * 2 * kPiD / kPhi;
                const Vec3 l =
                    frame.to_world(Vec3(float(std::sin(th) * std::cos(ph)),
                                        float(std::sin(th) * std::sin(ph)), float(std::cos(th))));
                // Distance to the sphere along l, and the turn of l across the pixel's step.
                const double b = dot(l, centre);
                const double dist = b - std::sqrt(std::max(0.0, b * b - (D * D - radius * radius)));
                const double step = 2 * half_pixel;
                const double turn = std::max(step * std::sqrt(1 - double(l.x) * l.x),
                                             step * std::sqrt(1 - double(l.y) * l.y)) /
                                    dist;
                const double cone = alpha + 0.5 * turn;
                const double dw = std::sin(th) * (alpha / kTheta) * (2 * kPiD / kPhi);
                const double g = radiance * reflectance(c, l, cone, true) / kPiD * l.z;
                mean += g * dw;
                second += g * g * dw;
                unfiltered += radiance * reflectance(c, l, 0, false) / kPiD * l.z * dw;
            }
        }
        const double sigma = std::sqrt(std::max(0.0, solid_angle * second - mean * mean));
        const double tolerance = 5 * sigma / std::sqrt(double(kSpp));
        std::printf(
            "[btf] area light, channel %d: rendered %.5f, cone-filtered %.5f +- %.5f "
            "(5 sigma), unfiltered %.5f\n",
            c, image[size_t(c)], mean, tolerance, unfiltered);
        EXPECT_NEAR(image[size_t(c)], mean, tolerance) << "channel " << c;
        EXPECT_GT(std::abs(unfiltered - mean), 2 * tolerance)
            << "the test must tell the filtered light from the unfiltered one";
    }
}

}  // namespace
