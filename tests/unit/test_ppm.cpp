// transient_ppm (plugins/integrators/transient_ppm): photon power, determinism, what it refuses,
// and the convergence rates of its surface and volume estimates against closed forms. The
// analytic checks it shares with every integrator are in the conformance matrix
// (test_integrators.cpp); error against time is measured in bench/.
#include <gtest/gtest.h>

#include "agreement_util.h"
#include "femto/testing/media.h"
#include "femto/testing/render.h"
#include "pulsed_fog.h"
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
    // Photons are traced in fixed chunks of 1024 and appended in chunk order; camera samples
    // read the map only: the render does not depend on the thread count. (64 x 64 pixels: 4096
    // photons per pass by default, four chunks.)
    const std::vector<std::pair<std::string, std::string>> defines = {
        {"res", "64"}, {"spp", "3"}, {"bins", "64"}};
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
        {"<integer name=\"photons_per_pass\" value=\"100000000\"/>",
         "photons_per_pass must lie in"},
        {"<float name=\"initial_radius\" value=\"0\"/>", "initial_radius must be positive"},
        {"<float name=\"initial_radius\" value=\"-1\"/>", "initial_radius must be positive"},
        {"<float name=\"initial_bandwidth\" value=\"nan\"/>", "initial_bandwidth"},
        {"<float name=\"initial_bandwidth\" value=\"0\"/>", "initial_bandwidth must be"},
        {"<string name=\"spatial_kernel\" value=\"cone\"/>", "unknown kernel \"cone\""},
        {"<float name=\"volume_alpha\" value=\"1\"/>", "volume_alpha must lie in (0, 1)"},
        {"<float name=\"volume_beta_t\" value=\"2\"/>", "volume_beta_t must lie in [0, 1]"},
        {"<float name=\"volume_initial_radius\" value=\"-0.5\"/>",
         "volume_initial_radius must be positive"},
    };
    for (const auto& [xml, message] : cases) {
        const std::string error = test::load_error(furnace(0.5, xml));
        EXPECT_NE(error.find(message), std::string::npos) << xml << ": " << error;
        EXPECT_EQ(error.rfind("<string>:", 0), 0u) << "no location: " << error;
    }
}

TEST(TransientPpm, RefusesASecondTimeSmoothing) {
    // The estimate smooths time itself: a kernel temporal filter would smooth twice, whether
    // the time bandwidth is the default or given.
    LoadOptions options;
    options.defines = {{"res", "8"}, {"spp", "1"}, {"tfilter", "kernel"}};
    for (const std::string bandwidth : {"", "<float name=\"initial_bandwidth\" value=\"0.1\"/>"}) {
        auto scene = load_scene_string(
            test::with_integrator("cornell-box", "transient_ppm", 0, false, bandwidth), options,
            test::kScenes);
        try {
            femto::testing::render_steady(*scene, 1);
            ADD_FAILURE() << "a kernel tfilter was accepted with \"" << bandwidth << "\"";
        } catch (const SceneError& e) {
            EXPECT_NE(std::string(e.what()).find("<tfilter type=\"histogram\"/>"),
                      std::string::npos)
                << e.what();
        }
    }
}

namespace {

// The time-of-flight plane lit by a Gaussian pulse: a point light of intensity 5 at height 1.5
// over a Lambertian plane of albedo 0.6 emits at time 1 + 0.15 N(0, 1); an orthographic camera at
// height 5 sees [-2, 2]^2 in 8 x 8 pixels, direct light only. Its cube is known in closed form:
// radiance rho / pi * I * H / d^3 arriving at camera time 5 + d + the emission time, d the
// distance from the light. The pulse makes every pixel's time profile smooth, as appendix 5.B's
// analysis assumes (a sharp arrival blurred by a kernel has a bias of first order in its width).
constexpr int kRes = 8, kBins = 800;
constexpr double kStart = 6.4, kWidth = 0.005, kH = 1.5, kI = 5, kRho = 0.6, kSigma = 0.15;

std::string pulsed_tof_plane_ppm(int passes) {
    return test::scene_xml(
        "<integrator type=\"transient_ppm\"><integer name=\"max_depth\" value=\"2\"/><integer "
        "name=\"photons_per_pass\" value=\"5000\"/><float name=\"initial_radius\" "
        "value=\"0.15\"/><float name=\"initial_bandwidth\" value=\"0.06\"/></integrator><sensor "
        "type=\"orthographic\"><transform name=\"to_world\"><scale x=\"2\" y=\"2\"/><lookat "
        "origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/></transform>" +
        test::independent_sampler(passes) +
        test::box_transient_film(kRes, kRes, kStart, kWidth, kBins) +
        "</sensor><shape type=\"rectangle\"><transform name=\"to_world\"><scale "
        "value=\"10\"/></transform><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"" +
        test::xml_number(kRho) +
        "\"/></bsdf></shape><emitter type=\"point\"><point name=\"position\" "
        "value=\"0,0,1.5\"/><float name=\"intensity\" value=\"5\"/><string name=\"pulse\" "
        "value=\"gaussian\"/><float name=\"pulse_sigma\" value=\"" +
        test::xml_number(kSigma) + "\"/><float name=\"time_offset\" value=\"1\"/></emitter>");
}

// The exact cube (one channel): each pixel's footprint sampled on a 48 x 48 grid, each point's
// radiance spread over the bins by the pulse.
std::vector<double> exact_pulsed_cube() {
    std::vector<double> cube(size_t(kRes) * kRes * kBins, 0.0);
    const int grid = 48;
    const double w = 4.0 / kRes;
    auto normal_cdf = [](double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); };
    for (int py = 0; py < kRes; ++py)
        for (int px = 0; px < kRes; ++px)
            for (int j = 0; j < grid; ++j)
                for (int i = 0; i < grid; ++i) {
                    // The image runs along -x and -y in world (the scene is symmetric in both).
                    const double x = 2 - (px + (i + 0.5) / grid) * w;
                    const double y = 2 - (py + (j + 0.5) / grid) * w;
                    const double d = std::sqrt(x * x + y * y + kH * kH);
                    const double L = kRho / M_PI * kI * kH / (d * d * d) / (grid * grid);
                    const double mean = 5 + d + 1;
                    for (int b = 0; b < kBins; ++b) {
                        const double lo = kStart + b * kWidth;
                        cube[(size_t(py) * kRes + size_t(px)) * kBins + size_t(b)] +=
                            L * (normal_cdf((lo + kWidth - mean) / kSigma) -
                                 normal_cdf((lo - mean) / kSigma));
                    }
                }
    return cube;
}

}  // namespace

TEST(TransientPpm, WindowReachesAsFarAsItsTimeKernel) {
    // Light arriving up to T_1 after the film's end still spreads into its last bins, so the
    // window the clocks cut paths at extends by T_1 (Integrator::time_reach()).
    auto scene = load_scene_string(pulsed_tof_plane_ppm(1));
    femto::testing::render_cube(*scene, 1, "ppm-reach");
    EXPECT_NEAR(scene->time_window().end, kStart + kBins * kWidth + 0.06, 1e-9);
}

TEST(TransientPpm, ErrorFallsAtTheRateOfAppendix5B) {
    // With alpha = 4/7 and beta_t = 1/3 both parts of the error fall as n^-4/7 (5.B.4): the
    // variance as n^-alpha, the squared bias (second order in R and T where the signal is
    // smooth) as n^-4(1-alpha)/3. Asymptotically: the schedule's own variance term,
    // (1/n^2) sum_j 1 / (R_j^2 T_j), falls with a local slope of -0.68 at n = 4, -0.58 at
    // n = 64..128 and -0.575 beyond, so the fit starts at 64 passes. The cube's summed squared
    // error against the closed form, averaged over 2 seeds at n = 64 ... 1024 passes (5000
    // photons each), must fall with a fitted log-log slope within 0.1 of -4/7.
    const std::vector<double> exact = exact_pulsed_cube();
    std::vector<double> log_n, log_mse;
    std::string points;
    for (int n = 64; n <= 1024; n *= 2) {
        double mse = 0;
        for (uint64_t seed = 1; seed <= 2; ++seed) {
            auto scene = load_scene_string(pulsed_tof_plane_ppm(n));
            const femto::testing::Cube cube = femto::testing::render_cube(*scene, seed, "ppm-rate");
            for (size_t c = 0; c < exact.size(); ++c) {
                const double e = cube.data[c * 3 + 1] - exact[c];
                mse += e * e / 2;
            }
        }
        log_n.push_back(std::log(double(n)));
        log_mse.push_back(std::log(mse));
        points += " " + std::to_string(n) + ":" + std::to_string(mse);
    }
    const double slope = test::fitted_slope(log_n, log_mse);
    ::testing::Test::RecordProperty("mse_slope", std::to_string(slope));
    std::printf("transient_ppm MSE slope %.3f (predicted -0.571); MSE by passes:%s\n", slope,
                points.c_str());
    EXPECT_NEAR(slope, -4.0 / 7.0, 0.1) << "MSE by passes:" << points;
}

namespace {

const std::string pulsed_fog_ppm =
    "<integrator type=\"transient_ppm\"><integer name=\"max_depth\" value=\"2\"/><integer "
    "name=\"photons_per_pass\" value=\"2000\"/><float name=\"volume_initial_radius\" "
    "value=\"0.3\"/><float name=\"initial_bandwidth\" value=\"0.1\"/></integrator>";

}  // namespace

TEST(TransientPpm, VolumeErrorFallsAtTheRateOfItsDerivation) {
    // Volume photons have a 3D spatial kernel: docs/photon-mapping.md derives alpha = 1/2,
    // beta_t = 1/4 (the defaults) and an error falling as n^-1/2. The profile's summed squared
    // error against the closed form, averaged over 16 seeds at n = 64 ... 1024 passes (2000
    // photons each), must fall with a fitted log-log slope within 0.1 of -1/2. (Over 8 seeds
    // the fit scatters by about 0.06: -0.46, -0.50, -0.44, -0.59 for seeds 1-8 ... 25-32.)
    const auto [slope, points] = test::pulsed_fog_error_slope(pulsed_fog_ppm, 16);
    EXPECT_NEAR(slope, -0.5, 0.1) << "MSE by passes:" << points;
}

namespace {

// The pulsed time-of-flight plane (as above) at 200 bins of 0.02, rendered with box kernels of
// fixed size (alpha 1 - 1e-6) R and T = 0.05, 20000 photons per pass.
constexpr int kBiasBins = 200;
constexpr double kBiasWidth = 0.02, kBiasT = 0.05;

std::string pulsed_tof_plane_fixed_kernels(double radius, int passes) {
    return test::scene_xml(
        "<integrator type=\"transient_ppm\"><integer name=\"max_depth\" value=\"2\"/><integer "
        "name=\"photons_per_pass\" value=\"20000\"/><float name=\"initial_radius\" value=\"" +
        test::xml_number(radius) + "\"/><float name=\"initial_bandwidth\" value=\"" +
        test::xml_number(kBiasT) +
        "\"/><float name=\"alpha\" value=\"0.999999\"/><string name=\"spatial_kernel\" "
        "value=\"box\"/><string name=\"temporal_kernel\" value=\"box\"/></integrator><sensor "
        "type=\"orthographic\"><transform name=\"to_world\"><scale x=\"2\" y=\"2\"/><lookat "
        "origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/></transform>" +
        test::independent_sampler(passes) +
        "<film type=\"transient\"><integer name=\"width\" value=\"8\"/><integer name=\"height\" "
        "value=\"8\"/><float name=\"start\" value=\"6.4\"/><float name=\"bin_width\" value=\"" +
        test::xml_number(kBiasWidth) + "\"/><integer name=\"bins\" value=\"" +
        std::to_string(kBiasBins) +
        "\"/><rfilter type=\"box\"/><tfilter "
        "type=\"histogram\"/></film></sensor><shape type=\"rectangle\"><transform "
        "name=\"to_world\"><scale value=\"10\"/></transform><bsdf type=\"diffuse\"><float "
        "name=\"reflectance\" value=\"0.6\"/></bsdf></shape><emitter type=\"point\"><point "
        "name=\"position\" value=\"0,0,1.5\"/><float name=\"intensity\" value=\"5\"/><string "
        "name=\"pulse\" value=\"gaussian\"/><float name=\"pulse_sigma\" value=\"0.15\"/><float "
        "name=\"time_offset\" value=\"1\"/></emitter>");
}

// The expected cube (one channel) of that render: each pixel's footprint on a 16 x 16 grid; at
// each of its points y the photons' light averaged over the disc of radius `radius` around y
// (72 points on equal-area rings: the disc's second moments exactly), each arrival spread by the
// pulse and the box of half-width `half_width` in time (0, 0: the exact cube).
std::vector<double> pulsed_plane_expectation(double radius, double half_width) {
    std::vector<double> cube(size_t(64) * kBiasBins, 0.0);
    const double sigma = 0.15;
    auto normal_cdf = [](double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); };
    auto normal_pdf = [](double z) { return std::exp(-0.5 * z * z) / std::sqrt(2 * M_PI); };
    // P(arrival < t) for an arrival at mean + sigma N(0, 1) + U(-h, h).
    auto cdf = [&](double t) {
        if (half_width == 0) return normal_cdf(t / sigma);
        auto psi = [&](double z) { return z * normal_cdf(z) + normal_pdf(z); };
        return sigma / (2 * half_width) *
               (psi((t + half_width) / sigma) - psi((t - half_width) / sigma));
    };
    std::vector<std::pair<double, double>> disc;  // offsets
    const int rings = radius > 0 ? 6 : 1, spokes = radius > 0 ? 12 : 1;
    for (int k = 0; k < rings; ++k)
        for (int m = 0; m < spokes; ++m) {
            const double r = radius * std::sqrt((k + 0.5) / rings),
                         a = 2 * M_PI * (m + 0.5) / spokes;
            disc.push_back({r * std::cos(a), r * std::sin(a)});
        }
    const int grid = 16;
    const double w = 0.5, reach = 6 * sigma + half_width;
    for (int py = 0; py < 8; ++py)
        for (int px = 0; px < 8; ++px)
            for (int j = 0; j < grid; ++j)
                for (int i = 0; i < grid; ++i)
                    for (const auto& [ox, oy] : disc) {
                        const double x = 2 - (px + (i + 0.5) / grid) * w + ox;
                        const double y = 2 - (py + (j + 0.5) / grid) * w + oy;
                        const double d = std::sqrt(x * x + y * y + kH * kH);
                        const double L = kRho / M_PI * kI * kH / (d * d * d) /
                                         (grid * grid * double(disc.size()));
                        const double mean = 5 + d + 1;
                        const int b0 = std::max(0, int((mean - reach - 6.4) / kBiasWidth));
                        const int b1 =
                            std::min(kBiasBins - 1, int((mean + reach - 6.4) / kBiasWidth));
                        double below = cdf(6.4 + b0 * kBiasWidth - mean);
                        for (int b = b0; b <= b1; ++b) {
                            const double upto = cdf(6.4 + (b + 1) * kBiasWidth - mean);
                            cube[(size_t(py) * 8 + size_t(px)) * kBiasBins + size_t(b)] +=
                                L * (upto - below);
                            below = upto;
                        }
                    }
    return cube;
}

}  // namespace

TEST(TransientPpm, BiasIsTheKernelsSmoothingOfTheSignal) {
    // A pass's estimate is, in expectation, the signal smoothed by its kernels: on a smooth
    // signal its bias is second order in the bandwidths, so that R_j and T_j shrinking by eq.
    // 5.58 shrink it as appendix 5.B predicts. With box kernels of fixed size the rendered cube
    // minus the exact one (the measured bias) is projected on the predicted bias (the smoothed
    // closed form minus the exact one), seed by seed (every pixel of a pass shares its photons,
    // so voxels' errors are correlated and the spread across 6 seeds gives the standard
    // error): the mean ratio must be 1 within 4 standard errors, at R = 0.4 and R = 0.2, whose
    // predicted biases differ by a factor of 3 (their spatial parts go as R^2, the time
    // kernel's is the same).
    const std::vector<double> exact = pulsed_plane_expectation(0, 0);
    double norm_previous = 0;
    for (const double radius : {0.4, 0.2}) {
        SCOPED_TRACE("R = " + std::to_string(radius));
        const std::vector<double> smoothed = pulsed_plane_expectation(radius, kBiasT);
        double bb = 0;
        for (size_t v = 0; v < exact.size(); ++v)
            bb += (smoothed[v] - exact[v]) * (smoothed[v] - exact[v]);
        std::vector<double> ratios;
        for (uint64_t seed = 1; seed <= 6; ++seed) {
            auto scene = load_scene_string(pulsed_tof_plane_fixed_kernels(radius, 64));
            const femto::testing::Cube cube = femto::testing::render_cube(*scene, seed, "ppm-bias");
            double mb = 0;
            for (size_t v = 0; v < exact.size(); ++v)
                mb += (cube.data[v * 3 + 1] - exact[v]) * (smoothed[v] - exact[v]);
            ratios.push_back(mb / bb);
        }
        const femto::testing::MeanAndError r = femto::testing::mean_and_error(ratios);
        std::printf("R %.2f: measured / predicted bias %.4f +- %.4f, |predicted| %.3g\n", radius,
                    r.mean, r.standard_error, std::sqrt(bb));
        EXPECT_LT(r.standard_error, 0.1) << "too noisy to see the bias";
        EXPECT_NEAR(r.mean, 1.0, 4 * r.standard_error);
        if (norm_previous > 0) {
            EXPECT_GT(norm_previous / std::sqrt(bb), 2.5);
        }
        norm_previous = std::sqrt(bb);
    }
}
