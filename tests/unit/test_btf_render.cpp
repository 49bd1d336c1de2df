// The `btf` material in full renders: a BTF is not reciprocal (BTF A's G_1 = (l.a)(v.b) with
// a != b), so the light tracer and BDPT, which evaluate it from the lights' side, must agree with
// the path tracer only if they evaluate it with the camera's side as the view (eval_adjoint()).
// And a transient render of it integrates to the steady one.
#include <gtest/gtest.h>

#include <string>

#include "agreement_util.h"
#include "btf/synth.h"
#include "btf_test_util.h"
#include "cube_util.h"
#include "scene_util.h"

namespace {

using namespace femto;
using namespace femto::test;

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
// of T_ck) G_k(l, z), per pixel, at every distance r = 1 ... 256.
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
    for (const int r : {1, 4, 16, 64, 256}) {
        const int n = 256 / r;
        const std::string xml =
            "<scene version=\"3.0.0\"><integrator type=\"direct\"/>"
            "<sensor type=\"orthographic\"><transform name=\"to_world\"><lookat origin=\"0, 0, 5\" "
            "target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform><sampler type=\"stratified\">"
            "<integer name=\"sample_count\" value=\"1\"/><boolean name=\"jitter\" "
            "value=\"false\"/></sampler><film type=\"hdrfilm\"><integer name=\"width\" value=\"" +
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
        EXPECT_LT(worst, 2e-5) << "r = " << r;
        std::printf("[btf] r = %3d (%3d x %3d pixels): worst relative error %.2g\n", r, n, n,
                    worst);
    }
}

}  // namespace
