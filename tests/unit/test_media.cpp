// Participating media in the path tracer against closed forms (issue 5, §3):
//  - the ballistic term of a point pulse in an infinite homogeneous medium, I e^(-sigma_t r)
//    / r^2 at t = eta r, seen on a small Lambertian detector;
//  - the exact single-scattering term along a camera ray (eq. 5.11 with one medium vertex),
//    for an isotropic and a forward-scattering (HG) phase function;
//  - a medium of index eta delays the ballistic arrival by (eta - 1) * length, in an infinite
//    medium and in a slab bounded by null surfaces (which also checks the transmittance of
//    both the camera path and the shadow connection through the slab's boundaries);
//  - bad medium parameters.
//
// Expected values. With a point light of intensity I at x_l, a camera ray x(s) = o + s d and
// max_depth = 2 (a camera segment and one connection), the radiance reaching the camera at
// time t is
//     L(t) = integral ds sigma_s p(d . w_l) I e^(-sigma_t (s + r(s))) / r(s)^2
//                        delta(t - eta (s + r(s)))          (r(s) = |x_l - x(s)|, w_l its
//                        direction)
// so a bin [t0, t1) holds the integral of the integrand over the s whose time falls in it;
// the test integrates it with the midpoint rule on 4e5 steps (relative error < 1e-6 here).
// A Lambertian detector of albedo rho at distance r from the light, lit at normal incidence,
// adds rho / pi * I e^(-sigma_t r) / r^2 times the camera segment's transmittance, at
// t = eta (camera distance + r).
//
// Tolerances: each bin is compared within 4 standard errors of its estimate, the standard error
// taken from the film's variance AOV (the variance of each pixel-bin mean over samples), plus
// 1e-4 relative for the quadrature. The ballistic amplitude is a binomial mean (the camera
// segment passes or scatters), its SE is from the same AOV.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "cube_util.h"
#include "femto/error.h"
#include "femto/host.h"
#include "femto/medium.h"
#include "femto/random.h"
#include "femto/testing/media.h"
#include "femto/time_sampling.h"
#include "scene_util.h"

using namespace femto;
using femto::test::Cube;
using femto::testing::expect_bins;
using femto::testing::Fog;
using femto::testing::single_scattering;
using V3 = femto::testing::Point3;

namespace {

constexpr double kPi = 3.14159265358979323846;

// An orthographic 1x1-pixel camera (footprint 0.002 wide) at `origin` looking at `target`,
// inside the fog (or not), with a transient film of `bins` bins from `start`.
std::string camera(const std::string& origin, const std::string& target, const std::string& up,
                   bool in_fog, double start, double width, int bins, int spp,
                   const std::string& strategies = "") {
    std::ostringstream s;
    s << "<integrator type=\"transient_path\"><integer name=\"max_depth\" value=\"2\"/>"
      << strategies
      << "</integrator><sensor type=\"orthographic\"><float name=\"near_clip\" value=\"0\"/>"
         "<transform name=\"to_world\"><scale x=\"0.001\" y=\"0.001\"/><lookat origin=\""
      << origin << "\" target=\"" << target << "\" up=\"" << up << "\"/></transform>"
      << (in_fog ? "<ref id=\"fog\"/>" : "")
      << "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"" << spp
      << "\"/></sampler><film type=\"transient\"><integer name=\"width\" value=\"1\"/>"
         "<integer name=\"height\" value=\"1\"/><float name=\"start\" value=\""
      << start << "\"/><float name=\"bin_width\" value=\"" << width
      << "\"/><integer name=\"bins\" value=\"" << bins
      << "\"/><string name=\"aovs\" value=\"variance\"/><rfilter type=\"box\"/></film></sensor>";
    return s.str();
}

std::string point_light(const std::string& position, double intensity) {
    std::ostringstream s;
    s << "<emitter type=\"point\"><point name=\"position\" value=\"" << position
      << "\"/><float name=\"intensity\" value=\"" << intensity << "\"/></emitter>";
    return s.str();
}

void check_single_scattering(const Fog& fog, const std::string& strategies = "") {
    // Camera at the origin looking along +x; the light 1 unit off the ray, at (2, 1, 0).
    const double start = 2.2, width = 0.05;
    const int bins = 80;
    const std::string xml =
        "<scene version=\"3.0.0\">" + fog.xml() +
        camera("0,0,0", "1,0,0", "0,0,1", true, start, width, bins, 20000, strategies) +
        point_light("2,1,0", 3.0) + "</scene>";
    auto scene = load_scene_string(xml);
    const auto [cube, variance] = femto::test::render_cube_and_variance(*scene, 5, "single");
    ASSERT_EQ(cube.T, bins);
    // Times past the window: s + r(s) grows with s, so s < start + bins * width suffices.
    const auto expected = single_scattering(fog, {0, 0, 0}, {1, 0, 0}, {2, 1, 0}, 3.0, 0.0,
                                            (start + bins * width) / fog.eta, start, width, bins);
    EXPECT_GT(expect_bins(cube, variance, expected), 60);
}

TEST(Media, SingleScatteringMatchesTheClosedFormIsotropic) { check_single_scattering(Fog{}); }

TEST(Media, SingleScatteringMatchesTheClosedFormForwardHG) {
    Fog fog;
    fog.g = 0.7;
    check_single_scattering(fog);
}

// Time-uniform distance sampling (ch. 5.6.1) changes where vertices fall, not the expected
// value: the same closed form holds with the `exponential` strategy, alone and mixed with
// mean-free-path sampling by MIS.
TEST(Media, SingleScatteringWithExponentialDistanceSampling) {
    check_single_scattering(Fog{},
                            "<distance type=\"exponential\"><float name=\"mean_vertices\" "
                            "value=\"2\"/></distance>");
    check_single_scattering(Fog{},
                            "<distance type=\"exponential\"/><boolean name=\"mis\" "
                            "value=\"true\"/>");
}

// The connection strategies (ch. 5.6.2) place the vertex that connects to the light
// themselves: line-to-point and equiangular alone, and shared with the distance strategy's
// vertices by MIS, give the same closed form, also in a medium of index 1.33 (the window
// limit of the connection vertex and its time depend on eta), and with the exponential
// distance strategy and forward scattering. (With max_depth 2 the angular strategy has no
// effect here; test_time_strategies.cpp covers it with multiple scattering.)
TEST(Media, SingleScatteringWithConnectionStrategies) {
    for (const char* connection : {"line_to_point", "equiangular"})
        for (const char* mis : {"false", "true"}) {
            SCOPED_TRACE(std::string(connection) + " mis=" + mis);
            check_single_scattering(Fog{}, std::string("<connection type=\"") + connection +
                                               "\"/><boolean name=\"mis\" value=\"" + mis + "\"/>");
        }
    Fog slow;
    slow.eta = 1.33;
    for (const char* connection : {"line_to_point", "equiangular"}) {
        SCOPED_TRACE(std::string(connection) + " eta=1.33");
        check_single_scattering(slow, std::string("<connection type=\"") + connection + "\"/>");
    }
    Fog forward;
    forward.g = 0.7;
    check_single_scattering(forward,
                            "<distance type=\"exponential\"/><connection "
                            "type=\"line_to_point\"/><boolean name=\"mis\" value=\"true\"/>");
}

// A Lambertian disk at z = 0 (albedo rho) under a point light at (0, 0, h), seen from 0.05
// above, all in an infinite medium: the ballistic term arrives at eta (h + 0.05) with
// amplitude rho / pi * I e^(-sigma_t h) / h^2 times the camera segment's e^(-sigma_t 0.05);
// single scattering in the camera's 0.05 gap arrives earlier, at eta (h - 0.05 + 2s) for s in
// [0, 0.05). Light heights are chosen so that the arrival lies mid-bin.
void check_ballistic(double eta, double h) {
    Fog fog;
    fog.eta = eta;
    const double rho = 0.5, intensity = 4.0, start = 0.5, width = 0.02;
    const int bins = 200;
    std::ostringstream light;
    light << "0,0," << h;
    const std::string xml =
        "<scene version=\"3.0.0\">" + fog.xml() +
        camera("0,0,0.05", "0,0,0", "0,1,0", true, start, width, bins, 4000) +
        "<shape type=\"disk\"><bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0.5\"/>"
        "</bsdf></shape>" +
        point_light(light.str(), intensity) + "</scene>";
    auto scene = load_scene_string(xml);
    const auto [cube, variance] = femto::test::render_cube_and_variance(*scene, 9, "ballistic");
    std::vector<double> expected = single_scattering(fog, {0, 0, 0.05}, {0, 0, -1}, {0, 0, h},
                                                     intensity, 0.0, 0.05, start, width, bins);
    const double arrival = eta * (h + 0.05);
    const int bin = int(std::floor((arrival - start) / width));
    const double in_bin = (arrival - start) / width - bin;
    ASSERT_TRUE(in_bin > 0.1 && in_bin < 0.9) << "arrival " << arrival << " near a bin edge";
    const double ballistic = rho / kPi * intensity * std::exp(-fog.sigma_t() * h) / (h * h) *
                             std::exp(-fog.sigma_t() * 0.05);
    expected[size_t(bin)] += ballistic;
    expect_bins(cube, variance, expected);
    // The ballistic bin is where the energy is (the gap's scattering is < 1 % of it).
    EXPECT_NEAR(cube.at(0, 0, bin, 0), ballistic, 0.02 * ballistic);
}

TEST(Media, BallisticTermOfAPointPulseInAnInfiniteMedium) {
    for (double h : {1.0, 2.0, 3.3}) {  // r = 1, 2, 3.3: e^(-sigma_t r) / r^2 over a range
        SCOPED_TRACE(h);
        check_ballistic(1.0, h);
    }
}

TEST(Media, IndexOfRefractionDelaysTheBallisticArrival) {
    // eta = 1.33: the arrival moves from 2.05 to 1.33 * 2.05, i.e. by (eta - 1) * 2.05.
    check_ballistic(1.33, 2.0);
}

TEST(Media, SlabBehindNullBoundariesAttenuatesAndDelays) {
    // A fog slab z in [1, 2] (a cube with a null material, interior = fog) between an
    // orthographic camera at z = 3 and a diffuse plane at z = 0 lit by a point light at
    // (0, 0.5, 4). Camera path and light connection each cross 1 unit of fog: the ballistic
    // light arrives at 3 + |(0, 0.5, 4)| + 2 (eta - 1) with amplitude
    // rho / pi * I cos / r^2 * e^(-2 sigma_t); scattering inside the slab arrives earlier.
    Fog fog;
    fog.eta = 1.5;
    const double rho = 0.5, intensity = 10.0, start = 6.0, width = 0.02;
    const int bins = 150;
    const std::string xml =
        "<scene version=\"3.0.0\">" + fog.xml() +
        camera("0,0,3", "0,0,0", "0,1,0", false, start, width, bins, 2000) +
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"5\"/></transform>"
        "<bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0.5\"/></bsdf></shape>"
        "<shape type=\"cube\"><transform name=\"to_world\"><scale x=\"5\" y=\"5\" z=\"0.5\"/>"
        "<translate z=\"1.5\"/></transform><bsdf type=\"null\"/><ref name=\"interior\" "
        "id=\"fog\"/></shape>" +
        point_light("0,0.5,4", intensity) + "</scene>";
    auto scene = load_scene_string(xml);
    const auto [cube, variance] = femto::test::render_cube_and_variance(*scene, 3, "slab");
    const double r = std::sqrt(0.25 + 16.0), cos_l = 4.0 / r;
    // Inside the slab the light path's length is 1 / cos_l (it crosses 1 unit of height).
    const double in_slab_light = 1.0 / cos_l;
    const double arrival = 3.0 + r + (fog.eta - 1) * (1.0 + in_slab_light);
    const double ballistic =
        rho / kPi * intensity * cos_l / (r * r) * std::exp(-fog.sigma_t() * (1.0 + in_slab_light));
    const int bin = int(std::floor((arrival - start) / width));
    double late = 0;  // nothing can arrive after the ballistic light with max_depth 2
    for (int t = bin + 1; t < cube.T; ++t) late += cube.at(0, 0, t, 0);
    EXPECT_EQ(late, 0.0);
    const double se = std::sqrt(double(variance.at(0, 0, bin, 0)));
    EXPECT_NEAR(cube.at(0, 0, bin, 0), ballistic, 4 * se + 1e-5 * ballistic)
        << "arrival " << arrival << " in bin " << bin;
    EXPECT_GT(ballistic, 0.0);
    // Earlier bins hold the slab's single scattering (times 3 - z + |x_l - x| + ...).
    double early = 0;
    for (int t = 0; t < bin; ++t) early += cube.at(0, 0, t, 0);
    EXPECT_GT(early, 0.0);
}

// ---------------------------------------------------------------------------------------------
// Distance strategies on their own

TEST(DistanceSampling, ExponentialSamplesMatchTheirPdf) {
    // Chi-square of 200000 samples in 40 equal-probability bins of the claimed exponential
    // (bins from the closed-form CDF; the last bin is the tail), for several rates; and the
    // pdf integrates to 1 (midpoint rule on [0, 40 / lambda], error < 1e-6).
    for (double lambda : {0.1, 1.0, 7.5}) {
        SCOPED_TRACE(lambda);
        double integral = 0;
        const double h = 40.0 / lambda / 400000;
        for (int i = 0; i < 400000; ++i)
            integral += DistanceSampler::pdf(lambda, (i + 0.5) * h) * h;
        EXPECT_NEAR(integral, 1.0, 1e-6);
        constexpr int kBins = 40, kSamples = 200000;
        std::vector<int> count(kBins, 0);
        Pcg32 rng(uint64_t(lambda * 1000), 3);
        for (int i = 0; i < kSamples; ++i) {
            const double r = DistanceSampler::sample(lambda, rng.next_double());
            const double cdf = 1 - DistanceSampler::survival(lambda, r);
            ++count[std::min(kBins - 1, int(cdf * kBins))];
        }
        double chi2 = 0;
        const double expected = double(kSamples) / kBins;
        for (int c : count) chi2 += (c - expected) * (c - expected) / expected;
        // 39 degrees of freedom: P(chi2 > 80) < 1e-4.
        EXPECT_LT(chi2, 80.0);
    }
}

// Fig. 5.7 (left) as a test: the times of a subpath's vertices, t_i = eta (r_1 + ... + r_i),
// are uniform in time under exponential distance sampling (appendix 5.C.1: their summed
// density is lambda / eta for any lambda), and the `exponential` strategy's rate gives
// mean_vertices vertices before the window's end. A uniform distance pdf (the thesis'
// counterexample) is not uniform in time.
TEST(DistanceSampling, ExponentialVertexTimesAreUniform) {
    Properties fog_props("homogeneous", {});
    fog_props.set_float("eta", 1.33);
    auto fog = std::static_pointer_cast<Medium>(
        create_object(PluginKind::Medium, "homogeneous", fog_props));
    Properties props("exponential", {});
    props.set_float("mean_vertices", 4.0);
    auto strategy = std::static_pointer_cast<DistanceSampler>(
        create_object(PluginKind::Distance, "exponential", props));
    const DistanceContext ctx{20.0};  // window [0, 20)
    const double lambda = strategy->rate(*fog, ctx);
    EXPECT_NEAR(lambda, 4.0 / 20.0 * 1.33, 1e-12);
    constexpr int kPaths = 50000, kBins = 20;
    auto histogram = [&](auto&& sample_distance, double& mean_count) {
        std::vector<int> count(kBins, 0);
        Pcg32 rng(17, 5);
        long total = 0;
        for (int p = 0; p < kPaths; ++p) {
            double t = 0;
            while (true) {
                t += 1.33 * sample_distance(rng.next_double());
                if (t >= ctx.window_end) break;
                ++count[int(t / ctx.window_end * kBins)];
                ++total;
            }
        }
        mean_count = double(total) / kPaths;
        double chi2 = 0;
        const double expected = double(total) / kBins;
        for (int c : count) chi2 += (c - expected) * (c - expected) / expected;
        return chi2;  // 19 degrees of freedom: P(chi2 > 45) < 1e-3, P(chi2 > 200) ~ 0
    };
    double mean_exponential = 0, mean_uniform = 0;
    const double chi2_exponential =
        histogram([&](double u) { return DistanceSampler::sample(lambda, u); }, mean_exponential);
    EXPECT_LT(chi2_exponential, 45.0);
    // The number of vertices in the window is Poisson with mean lambda * t_e / eta = 4.
    EXPECT_NEAR(mean_exponential, 4.0, 4 * std::sqrt(4.0 / kPaths));
    const double chi2_uniform =
        histogram([&](double u) { return u * 2.0 / lambda; }, mean_uniform);  // same mean distance
    EXPECT_GT(chi2_uniform, 200.0);
}

TEST(DistanceSampling, BadParameters) {
    EXPECT_NE(test::load_error(test::scene_xml("<integrator type=\"transient_path\"><distance "
                                               "type=\"exponential\"><float name=\"lambda\" "
                                               "value=\"-1\"/></distance></integrator><emitter "
                                               "type=\"point\"/>"))
                  .find("lambda"),
              std::string::npos);
    EXPECT_NE(
        test::load_error(test::scene_xml("<integrator type=\"transient_path\"><distance "
                                         "type=\"exponential\"><float name=\"lambda\" value=\"1\"/>"
                                         "<float name=\"mean_vertices\" value=\"2\"/></distance>"
                                         "</integrator><emitter type=\"point\"/>"))
            .find("not both"),
        std::string::npos);
    // mean_vertices needs a time window: a steady film has none.
    auto scene = load_scene_string(test::scene_xml(
        "<integrator type=\"transient_path\"><integer name=\"max_depth\" value=\"2\"/>"
        "<distance type=\"exponential\"/></integrator><emitter type=\"point\"/>"));
    try {
        render(*scene, RenderOptions{});
        ADD_FAILURE() << "expected a SceneError";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("mean_vertices"), std::string::npos);
    }
}

TEST(Media, DirectIntegratorRefusesMedia) {
    auto scene = load_scene_string(
        "<scene version=\"3.0.0\"><integrator type=\"direct\"/><medium type=\"homogeneous\" "
        "id=\"fog\"/><sensor type=\"perspective\"><ref id=\"fog\"/><film type=\"hdrfilm\">"
        "<integer name=\"width\" value=\"4\"/><integer name=\"height\" value=\"4\"/></film>"
        "</sensor><emitter type=\"point\"/></scene>");
    try {
        render(*scene, RenderOptions{});
        ADD_FAILURE() << "expected a SceneError";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("participating media"), std::string::npos);
    }
}

TEST(Media, RejectsBadParameters) {
    const std::string body = "<emitter type=\"point\"/>";
    EXPECT_NE(test::load_error(
                  test::scene_xml("<medium type=\"homogeneous\"><float name=\"sigma_a\" "
                                  "value=\"1\"/><float name=\"sigma_t\" value=\"1\"/></medium>" +
                                  body))
                  .find("not both"),
              std::string::npos);
    EXPECT_NE(test::load_error(test::scene_xml("<medium type=\"homogeneous\"><float name=\"eta\" "
                                               "value=\"0.5\"/></medium>" +
                                               body))
                  .find("eta"),
              std::string::npos);
    EXPECT_NE(test::load_error(test::scene_xml("<medium type=\"homogeneous\"><float "
                                               "name=\"sigma_s\" value=\"-1\"/></medium>" +
                                               body))
                  .find("sigma_s"),
              std::string::npos);
    EXPECT_NE(test::load_error(test::scene_xml("<medium type=\"homogeneous\"><rgb name=\"albedo\" "
                                               "value=\"1.5\"/></medium>" +
                                               body))
                  .find("albedo"),
              std::string::npos);
    EXPECT_NE(test::load_error(test::scene_xml("<medium type=\"homogeneous\" id=\"m\"/><shape "
                                               "type=\"rectangle\"><ref id=\"m\"/></shape>"))
                  .find("interior"),
              std::string::npos);
}

}  // namespace
