// transient_bdpt (issue 11): bidirectional path tracing in time.
//  - agreement with transient_path per pixel block and time group on the shipped scenes
//    (tests/unit/agreement_util.h: a chi-square with variances from independent renders);
//  - each strategy (s, t) alone, unweighted, estimates the same image of the paths it can
//    sample as the other strategies of the same length (the classic BDPT test), on surfaces
//    and in a medium;
//  - steady and transient films agree (the time integral is the steady image: conformance);
//  - bit-identical at 1 and 2 threads; bad input is a located error.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "agreement_util.h"
#include "cube_util.h"
#include "femto/host.h"

using namespace femto;
using namespace femto::test;

TEST(Bdpt, AgreesWithPathTracerOnCornellBox) {
    check_agreement({"cornell-box", 0, false, {{"res", "16"}, {"bins", "128"}}, 16, 8, 2, 16},
                    "transient_bdpt");
}

TEST(Bdpt, AgreesWithPathTracerOnSpheres) {
    check_agreement({"spheres", 0, false, {{"res", "16"}, {"bins", "160"}}, 16, 8, 2, 16},
                    "transient_bdpt");
}

TEST(Bdpt, AgreesWithPathTracerOnTofPlane) {
    // Enough samples that the image total is known to 0.25 %: a bias of a few percent under
    // the light (a wrong MIS weight for the point light) shows in it.
    check_agreement({"tof-plane", 2, true, {{"res", "16"}}, 64, 256, 2, 8}, "transient_bdpt");
}

TEST(Bdpt, AgreesWithPathTracerOnTofPlaneInWorldTime) {
    check_agreement({"tof-plane",
                     2,
                     true,
                     {{"res", "16"}, {"world_time", "true"}, {"start", "1.4"}},
                     64,
                     256,
                     2,
                     8},
                    "transient_bdpt");
}

TEST(Bdpt, AgreesWithPathTracerOnFluorescent) {
    check_agreement({"fluorescent", 0, true, {{"res", "16"}, {"bins", "150"}}, 64, 64, 2, 10},
                    "transient_bdpt");
}

// Media: the path tracer is the noisier side here, so it gets more samples, and in fog-object
// the equiangular connections that tame its shadow rays next to the point light (unbiased:
// test_time_strategies.cpp). Cells must be resolved to 15 %: the first light out of dense fog
// is a few rare samples per run in both. In fog-point the cells at the ball's rim are left out
// too: grazing paths through its thin edge make them rare events for the path tracer (at
// 4096 vs 65536 spp the interior cells of BDPT, the light tracer and the path tracer agree
// within 2 % per time group, while rim cells differ by 0.3-2.5x between any two renders).
TEST(Bdpt, AgreesWithPathTracerOnFogPoint) {
    AgreementCase c{"fog-point", 0, false, {{"res", "16"}, {"bins", "40"}}, 512, 16, 2, 5};
    c.resolved = 0.15;
    c.min_share = 0.05;
    check_agreement(c, "transient_bdpt");
}

AgreementCase fog_object_case() {
    AgreementCase c{"fog-object", 0, true, {{"res", "16"}, {"bins", "80"}}, 64, 16, 2, 8};
    c.path_children = "<connection type=\"equiangular\"/><boolean name=\"mis\" value=\"true\"/>";
    c.resolved = 0.15;
    return c;
}

TEST(Bdpt, AgreesWithPathTracerOnFogObject) {
    check_agreement(fog_object_case(), "transient_bdpt");
}

namespace {

// Renders `scene` with transient_bdpt's strategy (s, t) alone, unweighted, `runs` times.
// The Cornell box filled with a homogeneous medium (sigma_s 0.3, sigma_a 0.05: a few scattering
// events per path) bounded by a null cube just inside its walls, the camera outside it, and its
// lamp a sphere (radius 0.2) inside it. Every unweighted strategy then has finite variance: light
// samples of a sphere (cone sampling) stay bounded next to it, where those of the rectangular lamp
// grow as 1 / r^2 for medium vertices close to it, and so do connections to a camera in the medium.
std::string with_fog(const std::string& xml) {
    std::string out = replace_element(
        xml, "<!-- Light:", "</shape>",
        "<shape type=\"sphere\"><point name=\"center\" value=\"0,0.7,0\"/><float "
        "name=\"radius\" value=\"0.2\"/><bsdf type=\"diffuse\"><float name=\"reflectance\" "
        "value=\"0\"/></bsdf><emitter type=\"area\"><rgb name=\"radiance\" "
        "value=\"3,2.2,0.8\"/></emitter></shape>");
    return replace_element(out, "<sensor type=\"perspective\">", ">",
                           "<medium type=\"homogeneous\" id=\"fog\"><float name=\"sigma_s\" "
                           "value=\"0.3\"/><float name=\"sigma_a\" value=\"0.05\"/></medium>"
                           "<shape type=\"cube\"><transform name=\"to_world\"><scale "
                           "value=\"0.99\"/></transform><bsdf type=\"null\"/><ref "
                           "name=\"interior\" id=\"fog\"/></shape><sensor "
                           "type=\"perspective\">");
}

// With `fog`, in the medium of with_fog().
std::vector<Cube> strategy_runs(const std::string& scene, int max_depth, int s, int t,
                                const std::vector<std::pair<std::string, std::string>>& defines,
                                int runs, bool fog) {
    std::string xml = with_integrator(scene, "transient_bdpt", max_depth, false);
    if (fog) xml = with_fog(xml);
    xml = replace_element(xml, "<integrator", "</integrator>",
                          "<integrator type=\"transient_bdpt\"><integer name=\"max_depth\" "
                          "value=\"" +
                              std::to_string(max_depth) +
                              "\"/><integer name=\"strategy_s\" value=\"" + std::to_string(s) +
                              "\"/><integer name=\"strategy_t\" value=\"" + std::to_string(t) +
                              "\"/></integrator>");
    LoadOptions options;
    options.defines = defines;
    return render_runs(xml, options, runs, uint64_t(1000 + 100 * s), "strategy");
}

// Every strategy of paths with `segments` segments, alone and unweighted, estimates the same
// cube: each against light sampling (s = 1), the strategy of the path tracer's shadow rays.
// Strategies that find the light by chance (s = 0) or the camera (t = 1) are noisier: they get
// `spp` x `noisy` samples.
void check_strategies(const std::string& scene, bool fog, int segments,
                      const std::vector<std::pair<std::string, std::string>>& defines, int spp,
                      int noisy, int block, int group) {
    constexpr int kRuns = 16;
    const int n = segments + 1;  // vertices
    auto with_spp = [&](int count) {
        auto d = defines;
        d.push_back({"spp", std::to_string(count)});
        return d;
    };
    const Cells ref =
        cells_of(strategy_runs(scene, segments, 1, n - 1, with_spp(spp), kRuns, fog), block, group);
    for (int s = 0; s < n; ++s) {
        if (s == 1) continue;
        SCOPED_TRACE("strategy s=" + std::to_string(s) + " t=" + std::to_string(n - s));
        const int count = s == 0 || s == n - 1 ? spp * noisy : spp;
        const auto runs = strategy_runs(scene, segments, s, n - s, with_spp(count), kRuns, fog);
        expect_agree(cells_of(runs, block, group), ref, kRuns, scene + "_s" + std::to_string(s));
    }
}

}  // namespace

// The classic BDPT test: on the Cornell box (diffuse), paths of 3 segments by each of the four
// strategies (0,4), (1,3), (2,2), (3,1).
TEST(Bdpt, EachStrategyAloneEstimatesTheSameImage) {
    check_strategies("cornell-box", false, 3, {{"res", "16"}, {"bins", "128"}}, 16, 8, 4, 16);
}

// The same in a medium (with_fog()), paths of 2 segments (a scattering vertex in the fog or on a
// wall between the camera and the light): (0,3), (1,2), (2,1).
TEST(Bdpt, EachStrategyAloneEstimatesTheSameImageInAMedium) {
    check_strategies("cornell-box", true, 2, {{"res", "16"}, {"bins", "128"}}, 16, 8, 4, 16);
}

TEST(Bdpt, BitIdenticalAcrossThreadCounts) {
    const std::vector<std::pair<std::string, std::string>> defines = {
        {"res", "64"}, {"spp", "4"}, {"bins", "64"}};
    const auto a = image_with_threads("cornell-box", "transient_bdpt", defines, 1);
    const auto b = image_with_threads("cornell-box", "transient_bdpt", defines, 2);
    EXPECT_EQ(a, b);
}

// Time sampling: exponential distances (alone, and MIS-combined with mean free paths) on both
// subpaths, in fog-object, against the path tracer with steady sampling.
TEST(Bdpt, AgreesWithPathTracerWithExponentialDistances) {
    AgreementCase c = fog_object_case();
    c.children = "<distance type=\"exponential\"/><boolean name=\"mis\" value=\"true\"/>";
    check_agreement(c, "transient_bdpt");
    c.children = "<distance type=\"exponential\"/>";
    check_agreement(c, "transient_bdpt");
}

// Unsupported time-sampling strategies, max_depth 0, Russian roulette and a collimated emitter
// are located errors naming what is supported. (An orthographic sensor is rendered without the
// strategies t = 1: the conformance matrix's checks seen through one run on transient_bdpt.)
TEST(Bdpt, BadInputIsALocatedError) {
    const std::string base = with_integrator("fog-object", "transient_bdpt", 0, false);
    for (const char* strategy :
         {"<connection type=\"equiangular\"/>", "<connection type=\"line_to_point\"/>",
          "<angular type=\"time\"/>"}) {
        SCOPED_TRACE(strategy);
        const std::string xml = replace_element(
            base, "<integrator", "</integrator>",
            std::string("<integrator type=\"transient_bdpt\">") + strategy + "</integrator>");
        const std::string error = load_error(xml, {}, kScenes);
        EXPECT_NE(error.find("but only the steady connection=deterministic and angular=phase"),
                  std::string::npos)
            << error;
    }
    for (const char* param :
         {"<integer name=\"max_depth\" value=\"0\"/>", "<integer name=\"rr_depth\" value=\"5\"/>",
          "<string name=\"heuristic\" value=\"maximum\"/>"}) {
        SCOPED_TRACE(param);
        const std::string xml = replace_element(
            base, "<integrator", "</integrator>",
            std::string("<integrator type=\"transient_bdpt\">") + param + "</integrator>");
        EXPECT_NE(load_error(xml, {}, kScenes).find(":"), std::string::npos);
    }
    // The collimated laser-tank: refused when rendering starts.
    for (const char* scene : {"laser-tank"}) {
        auto loaded =
            load_scene_string(with_integrator(scene, "transient_bdpt", 0, false), {}, kScenes);
        try {
            render(*loaded, RenderOptions{});
            ADD_FAILURE() << scene << " was accepted";
        } catch (const SceneError& e) {
            EXPECT_NE(std::string(e.what()).find("collimated"), std::string::npos) << e.what();
        }
    }
}

// The MIS weights of all strategies of a path sum to 1: rendered with only the paths of L
// segments, the weighted sum over their strategies estimates the same cube as one of those
// strategies alone (light sampling, s = 1), on the Cornell box and in fog. A weight that does
// not sum to 1 over a path's strategies (e.g. one counting a strategy that cannot sample the
// path) biases the first.
TEST(Bdpt, MisWeightsOfAPathSumToOne) {
    constexpr int kRuns = 16;
    // In fog also with exponential distances MIS-combined with mean free paths: the weights then
    // hold distance densities that differ between the strategies of one path.
    const std::string exponential =
        "<distance type=\"exponential\"/><boolean name=\"mis\" value=\"true\"/>";
    for (const bool fog : {false, true})
        for (const std::string& distance : {std::string(), exponential})
            for (const int length : {2, 3}) {
                if (!fog && !distance.empty()) continue;
                SCOPED_TRACE(std::string(fog ? "fog" : "vacuum") + ", length " +
                             std::to_string(length) + (distance.empty() ? "" : ", exponential"));
                std::vector<std::pair<std::string, std::string>> defines = {
                    {"res", "16"}, {"bins", "128"}, {"spp", "16"}};
                const Cells alone = cells_of(
                    strategy_runs("cornell-box", length, 1, length, defines, kRuns, fog), 4, 16);
                std::string xml = with_integrator("cornell-box", "transient_bdpt", length, false);
                xml = replace_element(
                    xml, "<integrator", "</integrator>",
                    "<integrator type=\"transient_bdpt\"><integer "
                    "name=\"max_depth\" value=\"" +
                        std::to_string(length) + "\"/><integer name=\"path_length\" value=\"" +
                        std::to_string(length) + "\"/>" + distance + "</integrator>");
                if (fog) xml = with_fog(xml);
                LoadOptions options;
                options.defines = defines;
                const Cells weighted = cells_of(render_runs(xml, options, kRuns, 77, "mis"), 4, 16);
                expect_agree(weighted, alone, kRuns,
                             std::string("mis_") + (fog ? "fog" : "vacuum") +
                                 (distance.empty() ? "" : "_exp") + std::to_string(length));
            }
}
