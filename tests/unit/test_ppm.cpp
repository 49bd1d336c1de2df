// transient_ppm (plugins/integrators/transient_ppm): photon power, determinism, what it refuses.
// The analytic checks it shares with every integrator are in the conformance matrix
// (test_integrators.cpp); its convergence rate is measured in bench/.
#include <gtest/gtest.h>

#include "agreement_util.h"
#include "femto/testing/render.h"
#include "scene_util.h"

using namespace femto;

namespace {

// A closed diffuse sphere of albedo `albedo` and radius 3 emitting radiance 1 everywhere, seen
// from its centre.
std::string furnace(double albedo, const std::string& ppm) {
    return test::scene_xml(
        "<integrator type=\"transient_ppm\">" + ppm +
        "</integrator><sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/>" +
        test::independent_sampler(4) +
        "<film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" "
        "value=\"16\"/><rfilter type=\"box\"/></film></sensor><shape type=\"sphere\"><float "
        "name=\"radius\" value=\"3\"/><boolean name=\"flip_normals\" value=\"true\"/><bsdf "
        "type=\"diffuse\"><float name=\"reflectance\" value=\"" +
        test::xml_number(albedo) +
        "\"/></bsdf><emitter type=\"area\"><float name=\"radiance\" value=\"1\"/></emitter>"
        "</shape>");
}

}  // namespace

TEST(TransientPpm, FurnaceConservesPhotonPower) {
    // Inside the emitting sphere L = Le / (1 - albedo) at every depth; photon power is right
    // when the image mean equals it. The photon density is uniform, so the kernel adds no bias
    // beyond the sphere's curvature inside R (relative (R / 3)^2 / 8 ~ 1e-4 at R = 0.1). Every
    // pixel of a pass shares its photons, so the error comes from independent renders.
    const double albedo = 0.6, expected = 1.0 / (1.0 - albedo);
    std::vector<double> means;
    for (uint64_t seed = 1; seed <= 8; ++seed) {
        auto scene =
            load_scene_string(furnace(albedo,
                                      "<integer name=\"photons_per_pass\" value=\"20000\"/><float "
                                      "name=\"initial_radius\" value=\"0.1\"/>"));
        means.push_back(
            femto::testing::pixel_mean(femto::testing::render_steady(*scene, seed), 1).mean);
    }
    const femto::testing::MeanAndError m = femto::testing::mean_and_error(means);
    EXPECT_GT(m.standard_error, 0.0);
    EXPECT_NEAR(m.mean, expected, 4 * m.standard_error + 2e-4 * expected)
        << "standard error " << m.standard_error;
}

TEST(TransientPpm, SameImageOnOneAndTwoThreads) {
    // Photons are traced in fixed chunks and appended in chunk order; camera samples read the
    // map only: the render does not depend on the thread count.
    const std::vector<std::pair<std::string, std::string>> defines = {
        {"res", "24"}, {"spp", "3"}, {"bins", "64"}};
    const auto one = test::image_with_threads("cornell-box", "transient_ppm", defines, 1);
    const auto two = test::image_with_threads("cornell-box", "transient_ppm", defines, 2);
    double total = 0;
    for (float v : one) total += v;
    EXPECT_GT(total, 0.0);
    femto::testing::expect_same_image(one, two, "1 thread", "2 threads");
}

TEST(TransientPpm, RefusesBadParametersWithTheirLocation) {
    const std::pair<std::string, std::string> cases[] = {
        {"<float name=\"alpha\" value=\"0\"/>", "alpha must lie in (0, 1)"},
        {"<float name=\"alpha\" value=\"1\"/>", "alpha must lie in (0, 1)"},
        {"<float name=\"beta_t\" value=\"-0.1\"/>", "beta_t must lie in [0, 1]"},
        {"<float name=\"beta_t\" value=\"1.5\"/>", "beta_t must lie in [0, 1]"},
        {"<integer name=\"photons_per_pass\" value=\"0\"/>", "photons_per_pass must lie in"},
        {"<integer name=\"photons_per_pass\" value=\"-5\"/>", "photons_per_pass must lie in"},
        {"<float name=\"initial_radius\" value=\"0\"/>", "initial_radius must be positive"},
        {"<float name=\"initial_radius\" value=\"-1\"/>", "initial_radius must be positive"},
        {"<float name=\"initial_bandwidth\" value=\"nan\"/>", "initial_bandwidth"},
        {"<float name=\"initial_bandwidth\" value=\"0\"/>", "initial_bandwidth must be"},
        {"<string name=\"spatial_kernel\" value=\"cone\"/>", "unknown kernel \"cone\""},
    };
    for (const auto& [xml, message] : cases) {
        const std::string error = test::load_error(furnace(0.5, xml));
        EXPECT_NE(error.find(message), std::string::npos) << xml << ": " << error;
        EXPECT_EQ(error.rfind("<string>:", 0), 0u) << "no location: " << error;
    }
}

TEST(TransientPpm, RefusesASecondTimeSmoothingAndMedia) {
    // The estimate smooths time itself: a kernel temporal filter would smooth twice.
    std::string xml = test::with_integrator("cornell-box", "transient_ppm", 0, false);
    LoadOptions options;
    options.defines = {{"res", "8"}, {"spp", "1"}, {"tfilter", "kernel"}};
    auto scene = load_scene_string(xml, options, test::kScenes);
    try {
        femto::testing::render_steady(*scene, 1);
        ADD_FAILURE() << "a kernel tfilter was accepted";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("<tfilter type=\"histogram\"/>"), std::string::npos)
            << e.what();
    }
    // Surfaces only (volumetric photons are not there yet): a scene with media is refused.
    options.defines = {{"res", "8"}, {"spp", "1"}};
    auto fog = load_scene_string(test::with_integrator("fog-point", "transient_ppm", 0, false),
                                 options, test::kScenes);
    try {
        femto::testing::render_steady(*fog, 1);
        ADD_FAILURE() << "a scene with media was accepted";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("participating media"), std::string::npos) << e.what();
    }
}
