// The `btf` material in full renders: a BTF is not reciprocal (BTF A's G_1 = (l.a)(v.b) with
// a != b), so the light tracer and BDPT, which evaluate it from the lights' side, must agree with
// the path tracer only if they evaluate it with the camera's side as the view (eval_adjoint()).
// And a transient render of it integrates to the steady one.
#include <gtest/gtest.h>

#include <string>

#include "agreement_util.h"
#include "btf/synth.h"
#include "cube_util.h"
#include "scene_util.h"

namespace {

using namespace femto;
using namespace femto::test;

std::string btf_file() {
    btf::synth::Options o;
    o.format = btf::Format::Dfmf;
    o.width = 8;
    o.height = 4;
    o.directions = btf::ubo2003_directions();
    const std::string path = (femto::testing::temp_dir("btf-render") / "a.dfmf").string();
    btf::synth::write(path, o);
    return path;
}

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
