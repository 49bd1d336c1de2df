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

// transient_bdpt with each of `strategies` in its <integrator> against transient_bdpt with
// steady sampling, on fog_object_case()'s cells.
void agrees_with_steady_bdpt_on_fog_object(const std::vector<std::string>& strategies) {
    AgreementCase c = fog_object_case();
    c.reference = "transient_bdpt";
    c.path_children = "";
    c.spp_path = c.spp_light;
    for (const std::string& children : strategies) {
        SCOPED_TRACE(children);
        c.children = children;
        check_agreement(c, "transient_bdpt");
    }
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
                                int runs, bool fog, const std::string& sampler = "independent") {
    std::string xml = with_integrator(scene, "transient_bdpt", max_depth, false);
    if (fog) xml = with_fog(xml);
    // Independent numbers by default: an unweighted connection (s, t >= 2) between two walls has
    // infinite variance near the edge where they meet (G = cos cos / d^2), so a run's typical value
    // there sits below the mean, which rare large samples make up. The chi-square below assumes
    // finite variance; a stratified sampler (the box's ldsampler, whose dimensions BDPT aligns)
    // narrows the typical values until it flags that deficit (z ~ 6 in an edge cell, 8 runs of
    // 1024 spp, where the same strategy's mean agrees with independent numbers'), and the test
    // is about the strategies' expectations, not the sampler's.
    xml = replace_element(xml, "<sampler", "</sampler>",
                          "<sampler type=\"" + sampler +
                              "\"><integer name=\"sample_count\" value=\"$spp\"/></sampler>");
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

// An unbounded fog (sigma_s 0.4, sigma_a 0.05; isotropic, or `phase`) around the camera and a
// sphere lamp (radius 0.3, 3 units ahead): every vertex between the camera and the lamp is a medium
// vertex, and no boundary cuts a ray, so the connection strategy can place any of them.
std::string open_fog_scene(const std::string& integrator, int spp, const std::string& phase) {
    return "<scene version=\"3.0.0\"><medium type=\"homogeneous\" id=\"fog\"><float "
           "name=\"sigma_s\" value=\"0.4\"/><float name=\"sigma_a\" value=\"0.05\"/>" +
           phase + "</medium>" + integrator +
           "<sensor type=\"perspective\"><float name=\"fov\" value=\"50\"/><ref id=\"fog\"/>"
           "<transform name=\"to_world\"><lookat origin=\"0,0,0\" target=\"0,0,-1\" "
           "up=\"0,1,0\"/></transform><sampler type=\"independent\"><integer "
           "name=\"sample_count\" value=\"" +
           std::to_string(spp) +
           "\"/></sampler><film type=\"transient\"><integer name=\"width\" value=\"8\"/>"
           "<integer name=\"height\" value=\"8\"/><float name=\"bin_width\" value=\"0.25\"/>"
           "<integer name=\"bins\" value=\"48\"/><rfilter type=\"box\"/><tfilter "
           "type=\"histogram\"/></film></sensor><shape type=\"sphere\"><point name=\"center\" "
           "value=\"0.4,0.3,-3\"/><float name=\"radius\" value=\"0.3\"/><bsdf "
           "type=\"diffuse\"><float name=\"reflectance\" value=\"0\"/></bsdf><emitter "
           "type=\"area\"><rgb name=\"radiance\" value=\"4,3,2\"/></emitter></shape></scene>";
}

// transient_bdpt on paths of `segments` segments in open_fog_scene() with `children` in the
// integrator, 16 runs.
std::vector<Cube> open_fog_runs(int segments, const std::string& children, int spp, uint64_t seed,
                                const std::string& phase = "") {
    const std::string integrator =
        "<integrator type=\"transient_bdpt\"><integer name=\"max_depth\" value=\"" +
        std::to_string(segments) + "\"/><integer name=\"path_length\" value=\"" +
        std::to_string(segments) + "\"/>" + children + "</integrator>";
    return render_runs(open_fog_scene(integrator, spp, phase), LoadOptions{}, 16, seed, "open-fog");
}

// Strategy (s, t) alone, its last camera vertex placed by the connection strategy `connection`
// when `placed`.
std::vector<Cube> open_fog_strategy(int segments, int s, int t, bool placed,
                                    const std::string& connection, int spp,
                                    const std::string& phase = "") {
    return open_fog_runs(segments,
                         "<integer name=\"strategy_s\" value=\"" + std::to_string(s) +
                             "\"/><integer name=\"strategy_t\" value=\"" + std::to_string(t) +
                             "\"/><boolean name=\"strategy_placed\" value=\"" +
                             (placed ? "true" : "false") + "\"/><connection type=\"" + connection +
                             "\"/>",
                         spp, uint64_t(5000 + 100 * s + (placed ? 50 : 0)), phase);
}

}  // namespace

// The connection strategy's variants: the last camera vertex of strategy (s, t) placed on the
// camera ray toward light vertex s - 1, alone and unweighted, estimate the same cube as light
// sampling (1, t') alone, for paths of 2 and 3 segments. line_to_point's density does not
// follow the lamp's 1 / r^2 near it (equiangular's does), so its estimates have heavy tails
// there: at 64 spp the spread of 16 runs understates their variance, at 512 it does not.
TEST(Bdpt, PlacedStrategiesAloneEstimateTheSameImage) {
    constexpr int kRuns = 16;
    struct Case {
        int segments;
        const char* connection;
        int spp;
    };
    for (const Case& c : {Case{2, "equiangular", 64}, Case{2, "line_to_point", 64},
                          Case{3, "equiangular", 64}, Case{3, "line_to_point", 512}}) {
        const int n = c.segments + 1;
        const Cells ref =
            cells_of(open_fog_strategy(c.segments, 1, n - 1, false, c.connection, 64), 2, 8);
        for (int s = 1; s <= n - 2; ++s) {
            SCOPED_TRACE(std::string(c.connection) + " s=" + std::to_string(s) +
                         " t=" + std::to_string(n - s));
            const auto runs = open_fog_strategy(c.segments, s, n - s, true, c.connection, c.spp);
            expect_agree(cells_of(runs, 2, 8), ref, kRuns,
                         std::string("placed_") + c.connection + std::to_string(c.segments) + "_s" +
                             std::to_string(s));
        }
    }
}

// The MIS weights of all strategies of a path, the connection strategy's variants among them,
// sum to 1 (as in MisWeightsOfAPathSumToOne): in the open fog, paths of 2 and 3 segments with
// every strategy weighted estimate the same cube as light sampling alone, for equiangular
// placements, and line_to_point ones with exponential distances MIS-combined with mean free
// paths.
TEST(Bdpt, MisWeightsWithPlacedVerticesSumToOne) {
    constexpr int kRuns = 16;
    for (const int segments : {2, 3})
        for (const char* children :
             {"<connection type=\"equiangular\"/>",
              "<connection type=\"line_to_point\"/><distance type=\"exponential\"/><boolean "
              "name=\"mis\" value=\"true\"/>"}) {
            SCOPED_TRACE(std::string(children) + " " + std::to_string(segments));
            const Cells ref = cells_of(
                open_fog_strategy(segments, 1, segments, false, "deterministic", 64), 2, 8);
            const Cells weighted = cells_of(open_fog_runs(segments, children, 64, 77), 2, 8);
            expect_agree(weighted, ref, kRuns,
                         std::string("mis_placed_") +
                             (std::string(children).find("equiangular") != std::string::npos
                                  ? "equiangular"
                                  : "line_to_point") +
                             std::to_string(segments));
        }
}

// Time-angular directions (ch. 5.6.3) on both subpaths: light subpaths aim at the camera,
// camera subpaths at the light subpath's first vertex, each direction drawn after the distance
// it will be travelled. In the open fog, paths of 3 segments (two medium vertices, each leaving
// by a time-angular direction on one subpath or the other), each strategy (s, t) alone and
// unweighted estimates the same cube as light sampling with steady directions: the subpaths'
// weights divide by each direction's density given the distance drawn before it. Also with the
// directions and distances MIS-mixed with their steady counterparts. (0, 4) finds the lamp only
// by a direction that reaches it: 1024 spp.
TEST(Bdpt, TimeAngularStrategiesAloneEstimateTheSameImage) {
    constexpr int kRuns = 16, kSegments = 3;
    const Cells ref =
        cells_of(open_fog_strategy(kSegments, 1, kSegments, false, "deterministic", 64), 2, 8);
    for (const bool mis : {false, true})
        for (int s = 0; s <= kSegments; ++s) {
            const int t = kSegments + 1 - s;
            const std::string children =
                "<integer name=\"strategy_s\" value=\"" + std::to_string(s) +
                "\"/><integer name=\"strategy_t\" value=\"" + std::to_string(t) +
                "\"/><angular type=\"time\"/>" +
                (mis ? "<distance type=\"exponential\"/><boolean name=\"mis\" value=\"true\"/>"
                     : "");
            SCOPED_TRACE(children);
            const auto runs =
                open_fog_runs(kSegments, children, s == 0 ? 1024 : 64, uint64_t(7000 + 10 * s));
            expect_agree(
                cells_of(runs, 2, 8), ref, kRuns,
                std::string(mis ? "angular_mis" : "angular") + "_alone_s" + std::to_string(s));
        }
}

// The MIS weights with time-angular directions sum to 1 (as in MisWeightsOfAPathSumToOne). A
// direction's density depends on the distance drawn before it, which the path shows only where
// the next vertex is in the medium; the weights take the density at the segment's length, aimed
// at the path's own end points, the same for every strategy of a path (angular_densities()).
// In the open fog with backward scattering (HG g = -0.8: the time-angular densities differ
// most from the phase function's), paths of 3 and 4 segments with every strategy weighted
// estimate the same cube as light sampling alone: time-angular alone, MIS-mixed with
// exponential distances, and with the connection strategy's placed vertices; paths of 4
// segments only MIS-mixed (time-angular alone has weights f / q up to ~90 there, and at 256 spp
// the spread of 16 runs understates its variance; at 2048 spp all three agree). Paths of 2
// segments have a single medium vertex, whose densities toward the path's ends the weights do
// not use: emitter hits after a time-angular direction are left to the other strategies.
// Mutation checks: without angular_densities() (each strategy keeps its own subpaths' densities)
// the chi-square is 300-5000 against bounds near 150; dividing the light subpaths' time-angular
// directions by the phase function's density instead of their own gives 170-230 (the isotropic
// test above does not see that one: light tracing alone is too noisy there).
// Forward scattering (g = 0.8) is not used: there light sampling alone has heavy tails, and at
// 1024 spp its estimate was still rising toward BDPT's as the samples grew (up to 8192).
TEST(Bdpt, MisWeightsWithTimeAngularSumToOne) {
    constexpr int kRuns = 16;
    const std::string backward = "<phase type=\"hg\"><float name=\"g\" value=\"-0.8\"/></phase>";
    struct Variant {
        const char* name;
        const char* children;
    };
    for (const int segments : {3, 4}) {
        const Cells ref = cells_of(
            open_fog_strategy(segments, 1, segments, false, "deterministic", 512, backward), 2, 8);
        for (const Variant& v :
             {Variant{"time", "<angular type=\"time\"/>"},
              Variant{"time_mis",
                      "<angular type=\"time\"/><distance type=\"exponential\"/>"
                      "<boolean name=\"mis\" value=\"true\"/>"},
              Variant{"time_equiangular",
                      "<angular type=\"time\"/><connection type=\"equiangular\"/>"}}) {
            if (segments == 4 && std::string(v.name) != "time_mis") continue;
            SCOPED_TRACE(std::string(v.name) + " " + std::to_string(segments));
            const Cells weighted =
                cells_of(open_fog_runs(segments, v.children, 256, 91, backward), 2, 8);
            expect_agree(weighted, ref, kRuns,
                         std::string("mis_angular_") + v.name + std::to_string(segments));
        }
    }
}

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

// A low-discrepancy sampler stratifies every strategy, not only the subpath drawn first.
// Next-event estimation at the first hit alone (strategy (1, 2), unweighted) with subpaths of
// up to 8 segments, whose lengths vary from sample to sample: its per-pixel variance with the
// box's ldsampler over the one with independent numbers is 0.12 (median over the lit pixels);
// it was 0.44 when the light sample drew whichever dimension came after the two subpaths
// (before DimensionLayout), and near 1 it would be with no stratification. A pixel's ratio of
// two variances of 8 runs scatters as F(7, 7) (standard deviation of its log ~0.8), so the
// median of ~200 pixels' logs is known to about +-0.07: the bound 0.25 lies 10 of those from
// the aligned layout's 0.12 and 8 from the misaligned 0.44.
TEST(Bdpt, LowDiscrepancySamplerStratifiesLightSamples) {
    const std::vector<std::pair<std::string, std::string>> defines = {
        {"res", "16"}, {"bins", "64"}, {"spp", "64"}};
    auto pixel_variances = [&](const std::string& sampler) {
        const auto runs = strategy_runs("cornell-box", 8, 1, 2, defines, 8, false, sampler);
        return cells_of(runs, 1, runs[0].T).var;
    };
    const std::vector<double> ld = pixel_variances("ldsampler");
    const std::vector<double> independent = pixel_variances("independent");
    std::vector<double> ratios;
    for (size_t i = 0; i < ld.size(); ++i)
        if (independent[i] > 0) ratios.push_back(ld[i] / independent[i]);
    ASSERT_GT(ratios.size(), 150u);
    std::nth_element(ratios.begin(), ratios.begin() + ptrdiff_t(ratios.size() / 2), ratios.end());
    const double median = ratios[ratios.size() / 2];
    RecordProperty("median_variance_ratio", std::to_string(median));
    EXPECT_LT(median, 0.25) << "over " << ratios.size() << " pixels";
}

// Russian roulette on both subpaths (rr_depth 1: from their second segment on) estimates the
// same cube as none.
TEST(Bdpt, RussianRouletteKeepsTheImage) {
    AgreementCase c{"cornell-box", 0, false, {{"res", "16"}, {"bins", "128"}}, 16, 16, 2, 16};
    c.reference = "transient_bdpt";
    c.children = "<integer name=\"rr_depth\" value=\"1\"/>";
    check_agreement(c, "transient_bdpt");
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
// A collimated beam (a delta direction: its light vertex's position density moves to the next
// vertex) in a forward-scattering medium behind null boundaries of index 1.33. Against the
// light tracer: the path tracer finds the glow on the walls only when a bounce off a wall
// crosses the beam, rare events that at 16384 spp still leave 16-pixel blocks 0.3-3x off
// (while BDPT and the light tracer agree within 2-3 % on every lit block).
TEST(Bdpt, AgreesWithLightTracerOnLaserTank) {
    AgreementCase c{"laser-tank", 0,  false, {{"res", "16"}, {"bins", "60"}, {"bin_width", "1"}},
                    256,          64, 2,     10};
    c.reference = "transient_light";
    check_agreement(c, "transient_bdpt");
}

TEST(Bdpt, AgreesWithPathTracerWithExponentialDistances) {
    AgreementCase c = fog_object_case();
    c.children = "<distance type=\"exponential\"/><boolean name=\"mis\" value=\"true\"/>";
    check_agreement(c, "transient_bdpt");
    c.children = "<distance type=\"exponential\"/>";
    check_agreement(c, "transient_bdpt");
}

// Connection strategies: vertices placed on the camera rays toward each light vertex
// (equiangular; line_to_point with exponential distances), weighed by MIS with the rest.
// Against BDPT without them, which agrees with the path tracer above: the path tracer's rare
// first light out of the dense fog already takes the chi-square of that comparison to 583 of
// a bound of 621 (mean 481), which leaves no room to see a bias of the new strategies.
TEST(Bdpt, AgreesWithItselfWithConnectionStrategies) {
    agrees_with_steady_bdpt_on_fog_object(
        {"<connection type=\"equiangular\"/>",
         "<connection type=\"line_to_point\"/><distance type=\"exponential\"/><boolean "
         "name=\"mis\" value=\"true\"/>"});
}

// Every time-sampling strategy at once in fog-object (time-angular directions; exponential
// distances MIS-mixed with mean free paths; line_to_point placed vertices), and time-angular
// directions alone, against BDPT with steady sampling.
TEST(Bdpt, AgreesWithItselfWithTimeAngular) {
    agrees_with_steady_bdpt_on_fog_object(
        {"<angular type=\"time\"/>",
         "<angular type=\"time\"/><connection type=\"line_to_point\"/><distance "
         "type=\"exponential\"/><boolean name=\"mis\" value=\"true\"/>"});
}

// A vertex the connection strategy places at its ray's origin (a distance that rounds to 0)
// has no direction from it. With time-angular directions the weights then took the phase
// function of a NaN direction, and the sample was discarded with a warning (found in the
// bench: fog-object lit by a small sphere, line_to_point and time-angular, about 1 sample in
// 65000). Such vertices now add nothing, as in the walks. Regression: the render that met one
// (seed 19 as of this test's commit) warns of no discarded sample. If sampling changes, the
// seed may no longer meet one, and the test then checks less.
TEST(Bdpt, PlacedVertexOnTheRayOriginAddsNothing) {
    std::string xml = with_integrator(
        "fog-object", "transient_bdpt", 0, false,
        "<distance type=\"mean_free_path\"/><connection type=\"line_to_point\"/><angular "
        "type=\"time\"/><boolean name=\"mis\" value=\"true\"/>");
    xml = replace_element(xml, "<emitter type=\"point\">", "</emitter>",
                          "<shape type=\"sphere\"><point name=\"center\" x=\"0.1\" y=\"1.1\" "
                          "z=\"0.6\"/><float name=\"radius\" value=\"0.05\"/><emitter "
                          "type=\"area\"><rgb name=\"radiance\" value=\"254.648, 254.648, "
                          "254.648\"/></emitter></shape>");
    LoadOptions options;
    options.defines = {{"res", "8"},         {"spp", "64"},      {"bins", "80"},
                       {"bin_width", "0.1"}, {"sigma_s", "0.9"}, {"g", "0.8"}};
    auto scene = load_scene_string(xml, options, kScenes);
    ::testing::internal::CaptureStderr();
    const Cube cube = render_cube(*scene, 19, "placed-origin");
    const std::string log = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(log.find("NaN or infinite"), std::string::npos) << log;
    EXPECT_GT(cube.T, 0);
}

// max_depth 0, a negative rr_depth, an unknown heuristic and strategy_placed without a strategy
// that has a placed variant are located errors naming what is supported. (Every time-sampling
// strategy is supported. An orthographic sensor is rendered without the
// strategies t = 1: the conformance matrix's checks seen through one run on transient_bdpt.)
TEST(Bdpt, BadInputIsALocatedError) {
    const std::string base = with_integrator("fog-object", "transient_bdpt", 0, false);
    for (const char* param :
         {"<integer name=\"max_depth\" value=\"0\"/>", "<integer name=\"rr_depth\" value=\"-1\"/>",
          "<string name=\"heuristic\" value=\"maximum\"/>",
          // the connection strategy's variant of no strategy, or with no connection strategy
          "<boolean name=\"strategy_placed\" value=\"true\"/>",
          "<integer name=\"strategy_s\" value=\"1\"/><integer name=\"strategy_t\" "
          "value=\"2\"/><boolean name=\"strategy_placed\" value=\"true\"/>",
          // strategies that have no connection-strategy variant
          "<integer name=\"strategy_s\" value=\"0\"/><integer name=\"strategy_t\" "
          "value=\"3\"/><boolean name=\"strategy_placed\" value=\"true\"/><connection "
          "type=\"equiangular\"/>",
          "<integer name=\"strategy_s\" value=\"2\"/><integer name=\"strategy_t\" "
          "value=\"1\"/><boolean name=\"strategy_placed\" value=\"true\"/><connection "
          "type=\"equiangular\"/>"}) {
        SCOPED_TRACE(param);
        const std::string xml = replace_element(
            base, "<integrator", "</integrator>",
            std::string("<integrator type=\"transient_bdpt\">") + param + "</integrator>");
        EXPECT_NE(load_error(xml, {}, kScenes).find(":"), std::string::npos);
    }
}

// The MIS weights of all strategies of a path sum to 1: rendered with only the paths of L
// segments, the weighted sum over their strategies estimates the same cube as one of those
// strategies alone (light sampling, s = 1), on the Cornell box and in fog. A weight that does
// not sum to 1 over a path's strategies (e.g. one counting a strategy that cannot sample the
// path) biases the first. Paths of 4 segments reach the subpaths' far sums with more than one
// strategy in them (Bdpt::far_sums(): dropping them, or a heuristic applied to them wrongly,
// fails here at length 4 only).
TEST(Bdpt, MisWeightsOfAPathSumToOne) {
    constexpr int kRuns = 16;
    // In fog also with exponential distances MIS-combined with mean free paths: the weights then
    // hold distance densities that differ between the strategies of one path.
    const std::string exponential =
        "<distance type=\"exponential\"/><boolean name=\"mis\" value=\"true\"/>";
    for (const bool fog : {false, true})
        for (const std::string& distance : {std::string(), exponential})
            for (const int length : {2, 3, 4}) {
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
