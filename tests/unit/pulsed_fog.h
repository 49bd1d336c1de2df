// The pulsed-fog single-scattering setup that the volume estimators' rate tests share
// (transient_ppm's volume photons, transient_beams): its scene around an integrator, the exact
// profile, and the least-squares slope of log error against log passes.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "femto/host.h"
#include "femto/testing/media.h"
#include "femto/testing/render.h"
#include "scene_util.h"

namespace femto::test {

// Single scattering in fog (sigma_a 0.1, sigma_s 0.5, Henyey-Greenstein g = 0.3) along the ray
// of a one-pixel orthographic camera at the origin looking along +x, lit by a point light of
// intensity 3 at (2, 1, 0) that emits at time 1 + 0.15 N(0, 1): the closed form of
// femto/testing/media.h spread by the pulse, smooth in time as appendix 5.B's analysis assumes.
constexpr int kFogBins = 300;
constexpr double kFogStart = 2.6, kFogWidth = 0.02, kFogSigma = 0.15;

inline femto::testing::Fog rate_fog() {
    femto::testing::Fog fog;
    fog.g = 0.3;
    return fog;
}

// The exact single-scattering profile: the delta-pulse closed form on 20000 steps along the
// ray, each step's arrival spread over the bins by the Gaussian pulse.
inline std::vector<double> exact_pulsed_fog() {
    const femto::testing::Fog fog = rate_fog();
    std::vector<double> out(kFogBins, 0.0);
    const double end = kFogStart + kFogBins * kFogWidth;
    const int steps = 20000;
    const double h = end / steps;
    auto normal_cdf = [](double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); };
    for (int n = 0; n < steps; ++n) {
        const double s = (n + 0.5) * h, r = std::hypot(2 - s, 1.0);
        const double value = fog.sigma_s * fog.phase((2 - s) / r) * 3 *
                             std::exp(-fog.sigma_t() * (s + r)) / (r * r) * h;
        const double mean = 1 + fog.eta * (s + r);
        for (int b = 0; b < kFogBins; ++b) {
            const double lo = kFogStart + b * kFogWidth;
            if (lo + kFogWidth < mean - 8 * kFogSigma || lo > mean + 8 * kFogSigma) continue;
            out[size_t(b)] += value * (normal_cdf((lo + kFogWidth - mean) / kFogSigma) -
                                       normal_cdf((lo - mean) / kFogSigma));
        }
    }
    return out;
}

/// The scene of the pulsed fog with `integrator` (an <integrator> element) and `passes` samples.
inline std::string pulsed_fog_scene(const std::string& integrator, int passes) {
    return test::scene_xml(
        rate_fog().xml() + integrator +
        "<sensor type=\"orthographic\"><float name=\"near_clip\" value=\"0\"/><transform "
        "name=\"to_world\"><scale x=\"0.001\" y=\"0.001\"/><lookat origin=\"0,0,0\" "
        "target=\"1,0,0\" up=\"0,0,1\"/></transform><ref id=\"fog\"/>" +
        test::independent_sampler(passes) +
        test::box_transient_film(1, 1, kFogStart, kFogWidth, kFogBins) +
        "</sensor><emitter type=\"point\"><point name=\"position\" value=\"2,1,0\"/><float "
        "name=\"intensity\" value=\"3\"/><string name=\"pulse\" value=\"gaussian\"/><float "
        "name=\"pulse_sigma\" value=\"" +
        test::xml_number(kFogSigma) + "\"/><float name=\"time_offset\" value=\"1\"/></emitter>");
}

// Least-squares slope of y against x.
inline double fitted_slope(const std::vector<double>& x, const std::vector<double>& y) {
    const double k = double(x.size());
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (size_t i = 0; i < x.size(); ++i)
        sx += x[i], sy += y[i], sxx += x[i] * x[i], sxy += x[i] * y[i];
    return (k * sxy - sx * sy) / (k * sxx - sx * sx);
}

/// The pulsed fog's error against its closed form at 64, 128, ..., 1024 passes of
/// `integrator` (an <integrator> element): the profile's summed squared
/// error averaged over seeds 1..`seeds`, and the least-squares slope of its log against log
/// passes. Prints and records the slope; returns it with the errors as text.
inline std::pair<double, std::string> pulsed_fog_error_slope(const std::string& integrator,
                                                             int seeds) {
    const std::vector<double> exact = exact_pulsed_fog();
    std::vector<double> log_n, log_mse;
    std::string points;
    for (int n = 64; n <= 1024; n *= 2) {
        double mse = 0;
        for (int seed = 1; seed <= seeds; ++seed) {
            auto scene = load_scene_string(pulsed_fog_scene(integrator, n));
            const femto::testing::Cube cube =
                femto::testing::render_cube(*scene, uint64_t(seed), "fog-rate");
            for (size_t b = 0; b < exact.size(); ++b) {
                const double e = cube.data[b * 3] - exact[b];
                mse += e * e / seeds;
            }
        }
        log_n.push_back(std::log(double(n)));
        log_mse.push_back(std::log(mse));
        points += " " + std::to_string(n) + ":" + std::to_string(mse);
    }
    const double slope = fitted_slope(log_n, log_mse);
    ::testing::Test::RecordProperty("mse_slope", std::to_string(slope));
    std::printf("MSE slope %.3f; MSE by passes:%s\n", slope, points.c_str());
    return {slope, points};
}

}  // namespace femto::test
