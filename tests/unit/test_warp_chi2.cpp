// Chi-square tests of the host's sampling routines (femto::warp) against their documented
// densities, plus self-tests of the chi-square harness (tests/unit/chi2.h): its p-values
// against closed forms, and its power to reject a slightly wrong density.
//
// Directions are binned over (cos theta, phi); 2D points over their own square domain. Every
// test draws 1e6 samples with a fixed seed; a test fails when p < the Šidák-corrected level
// for 1% over the kWarpTests tests of this file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "chi2.h"
#include "femto/warp.h"

namespace {

using femto::Vec2;
using femto::Vec3;
using namespace femto_test;

constexpr int kWarpTests = 10;  // the WarpChi2 tests below (all use `level()`)

double level() { return corrected_significance(kWarpTests); }

Vec2 next_2d(femto::Pcg32& rng) {
    const float a = rng.next_float();
    return {a, rng.next_float()};
}

void expect_pass(const Chi2Result& r, const char* what) {
    std::printf("[chi2] %s: %s (level %.3g)\n", what, r.describe().c_str(), level());
    EXPECT_TRUE(r.error.empty()) << r.describe();
    EXPECT_GT(r.p_value, level()) << r.describe();
    // Every sample is returned, so the density must integrate to one (quadrature tolerance
    // summed over the bins is < 2e-5; 1e-4 allows 5x that).
    EXPECT_NEAR(r.pdf_integral, 1.0, 1e-4) << r.describe();
    EXPECT_EQ(r.histogrammed, r.samples);
}

/// A direction sampler over (cos theta, phi) on the whole sphere.
template <typename Warp, typename Pdf>
Chi2Result direction_test(const Warp& warp, const Pdf& pdf, const std::string& name,
                          Chi2Options o = Chi2Options{}) {
    o.seed = seed_from_name(name);
    return chi2_test(
        o,
        [&](femto::Pcg32& rng) -> std::optional<std::pair<double, double>> {
            return sphere_coords(warp(next_2d(rng)));
        },
        [&](double z, double phi) { return static_cast<double>(pdf(sphere_direction(z, phi))); });
}

TEST(WarpChi2, CosineHemisphere) {
    const Chi2Result r = direction_test(femto::warp::square_to_cosine_hemisphere,
                                        femto::warp::cosine_hemisphere_pdf, "cosine hemisphere");
    expect_pass(r, "cosine hemisphere");
}

TEST(WarpChi2, UniformHemisphere) {
    const Chi2Result r = direction_test(femto::warp::square_to_uniform_hemisphere,
                                        femto::warp::uniform_hemisphere_pdf, "uniform hemisphere");
    expect_pass(r, "uniform hemisphere");
}

TEST(WarpChi2, UniformSphere) {
    const Chi2Result r = direction_test(
        femto::warp::square_to_uniform_sphere,
        [](const Vec3&) { return femto::warp::uniform_sphere_pdf(); }, "uniform sphere");
    expect_pass(r, "uniform sphere");
}

/// Cones: the domain is restricted to cos theta in [cos_max, 1] so that narrow cones are
/// resolved by all the cos theta bins (samples outside the cone would be counted as errors).
void cone_test(float cos_max) {
    char what[64];
    std::snprintf(what, sizeof what, "uniform cone cos_max=%g", cos_max);
    Chi2Options o;
    o.x0 = cos_max;
    o.nx = 32;
    const Chi2Result r = direction_test(
        [&](Vec2 u) { return femto::warp::square_to_uniform_cone(u, cos_max); },
        [&](const Vec3& v) {
            // The density inside the cone; the quadrature nodes lie in [cos_max, 1] but may
            // round to just below cos_max in float.
            return femto::warp::uniform_cone_pdf(Vec3(v.x, v.y, std::max(v.z, cos_max)), cos_max);
        },
        what, o);
    expect_pass(r, what);
}

TEST(WarpChi2, UniformConeWide) { cone_test(-0.3f); }
TEST(WarpChi2, UniformConeNarrow) { cone_test(0.95f); }

TEST(WarpChi2, UniformDisk) {
    Chi2Options o;
    o.nx = o.ny = 40;
    o.x0 = o.y0 = -1;
    o.x1 = o.y1 = 1;
    o.seed = seed_from_name("uniform disk");
    const Chi2Result r = chi2_test(
        o,
        [](femto::Pcg32& rng) -> std::optional<std::pair<double, double>> {
            const Vec2 p = femto::warp::square_to_uniform_disk(next_2d(rng));
            return std::make_pair(double(p.x), double(p.y));
        },
        [](double x, double y) { return x * x + y * y <= 1.0 ? 1.0 / kPi : 0.0; });
    expect_pass(r, "uniform disk");
}

// The concentric map evaluates its sine and cosine by polynomials on [-pi/4, pi/4] (no libm
// call). Against the map in double precision, over a 1025 x 1025 grid of the square: each
// coordinate within 4 ulps of the radius. Rounding allows about 3 (the ratio's division and
// the angle's product, half an ulp each; the polynomials' 1.1 measured over 2^21 angles; the
// radius' product, half), so a wrong coefficient or a swapped wedge fails by far more.
TEST(WarpDisk, ConcentricMapMatchesItsClosedFormToTheUlp) {
    const int n = 1024;
    double worst = 0;
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
            const Vec2 u{float(i) / n, float(j) / n};
            const Vec2 p = femto::warp::square_to_uniform_disk(u);
            const double a = 2.0 * u.x - 1.0, b = 2.0 * u.y - 1.0;
            if (a == 0 && b == 0) {
                EXPECT_EQ(p.x, 0.f);
                EXPECT_EQ(p.y, 0.f);
                continue;
            }
            const bool wide = a * a > b * b;
            const double r = wide ? a : b;
            const double phi = wide ? kPi / 4 * (b / a) : kPi / 2 - kPi / 4 * (a / b);
            const float fr = float(std::abs(r));
            const double ulp = double(std::nextafter(fr, 2.f) - fr);
            worst = std::max({worst, std::abs(p.x - r * std::cos(phi)) / ulp,
                              std::abs(p.y - r * std::sin(phi)) / ulp});
        }
    EXPECT_LE(worst, 4.0) << "largest error, in ulps of the radius";
}

TEST(WarpChi2, UniformTriangle) {
    Chi2Options o;
    o.nx = o.ny = 40;
    o.x0 = o.y0 = 0;
    o.x1 = o.y1 = 1;
    o.seed = seed_from_name("uniform triangle");
    const Chi2Result r = chi2_test(
        o,
        [](femto::Pcg32& rng) -> std::optional<std::pair<double, double>> {
            const Vec2 b = femto::warp::square_to_uniform_triangle(next_2d(rng));
            EXPECT_GE(b.x, 0.f);
            EXPECT_GE(b.y, 0.f);
            EXPECT_LE(b.x + b.y, 1.f + 1e-6f);
            return std::make_pair(double(b.x), double(b.y));
        },
        [](double b1, double b2) { return b1 + b2 <= 1.0 ? 2.0 : 0.0; });
    expect_pass(r, "uniform triangle");
}

/// sample_discrete_cdf: the index follows the probabilities (zero-probability entries are
/// never chosen) and the rescaled u is uniform within the chosen entry. Both at once: the
/// point (index + rescaled u) has density p[floor(x)] over [0, n), 4 bins per entry.
TEST(WarpChi2, DiscreteCdf) {
    const std::vector<double> p = {0.1, 0.0, 0.25, 0.05, 0.3, 0.0, 0.2, 0.1};
    const uint32_t n = static_cast<uint32_t>(p.size());
    std::vector<float> cdf(n + 1, 0.f);
    double acc = 0;
    for (uint32_t i = 0; i < n; ++i) cdf[i + 1] = static_cast<float>(acc += p[i]);
    cdf[n] = 1.f;
    Chi2Options o;
    o.nx = 4 * static_cast<int>(n);
    o.ny = 4;
    o.x0 = 0;
    o.x1 = n;
    o.y0 = 0;
    o.y1 = 1;
    o.seed = seed_from_name("discrete cdf");
    const Chi2Result r = chi2_test(
        o,
        [&](femto::Pcg32& rng) -> std::optional<std::pair<double, double>> {
            float u = rng.next_float();
            const uint32_t i = femto::warp::sample_discrete_cdf(cdf.data(), n, u);
            EXPECT_LT(i, n);
            EXPECT_GT(p[i], 0.0) << "picked an empty entry " << i;
            EXPECT_GE(u, 0.f);
            EXPECT_LT(u, 1.f);
            return std::make_pair(i + double(u), double(rng.next_float()));
        },
        [&](double x, double) {
            const int i = std::clamp(static_cast<int>(std::floor(x)), 0, static_cast<int>(n) - 1);
            return p[i];
        });
    expect_pass(r, "discrete cdf");
}

/// AliasTable: as sample_discrete_cdf above, the index follows the weights (never one of
/// weight 0) and the rescaled u is uniform within the entry, for two tables: a small one with
/// empty entries, and one of 1000 entries of very unequal weights (1 to 1000, as the
/// triangles of a mesh light), binned over its first 40 entries and the rest together.
void alias_chi2(const std::vector<double>& weights, int bins_x, const char* name) {
    const femto::warp::AliasTable table(weights);
    const uint32_t n = static_cast<uint32_t>(weights.size());
    double sum = 0;
    for (double w : weights) sum += w;
    ASSERT_EQ(table.size(), n);
    // x = index + u over [0, n) for the small table; the large one folds every index >= 39
    // into [39, 40) so that the bins keep enough expected counts.
    const uint32_t shown = std::min<uint32_t>(n, 40);
    Chi2Options o;
    o.nx = bins_x;
    o.ny = 4;
    o.x0 = 0;
    o.x1 = shown;
    o.y0 = 0;
    o.y1 = 1;
    o.seed = seed_from_name(name);
    const Chi2Result r = chi2_test(
        o,
        [&](femto::Pcg32& rng) -> std::optional<std::pair<double, double>> {
            float u = rng.next_float();
            const uint32_t i = table.sample(u);
            EXPECT_LT(i, n);
            EXPECT_GT(weights[i], 0.0) << "picked an empty entry " << i;
            EXPECT_GE(u, 0.f);
            EXPECT_LT(u, 1.f);
            const double x = i < shown - 1 ? i + double(u) : (shown - 1) + double(u);
            return std::make_pair(x, double(rng.next_float()));
        },
        [&](double x, double) {
            const uint32_t i = std::min(static_cast<uint32_t>(std::floor(x)), shown - 1);
            if (i < shown - 1) return weights[i] / sum;
            double rest = 0;
            for (uint32_t k = shown - 1; k < n; ++k) rest += weights[k];
            return rest / sum;
        });
    expect_pass(r, name);
}

TEST(WarpChi2, AliasTableSmall) {
    alias_chi2({0.1, 0.0, 0.25, 0.05, 0.3, 0.0, 0.2, 0.1}, 32, "alias table, 8 entries");
}

TEST(WarpChi2, AliasTableUnequal) {
    std::vector<double> w(1000);
    femto::Pcg32 rng(seed_from_name("alias weights"), 3);
    for (double& x : w) x = 1.0 + 999.0 * double(rng.next_float());
    w[5] = 0.0;
    alias_chi2(w, 160, "alias table, 1000 unequal entries");
}

TEST(AliasTable, RejectsWeightsWithoutAPositiveFiniteSum) {
    EXPECT_THROW(femto::warp::AliasTable({0.0, 0.0}), std::invalid_argument);
    EXPECT_THROW(femto::warp::AliasTable({1.0, -1.0}), std::invalid_argument);
    EXPECT_THROW(femto::warp::AliasTable({1.0, NAN}), std::invalid_argument);
    EXPECT_THROW(femto::warp::AliasTable(std::vector<double>{}), std::invalid_argument);
}

// ---- the harness itself ----------------------------------------------------------------------

TEST(Chi2Harness, PValuesMatchClosedForms) {
    // dof = 2: P(X > x) = exp(-x / 2).  dof = 1: P(X > x) = erfc(sqrt(x / 2)).
    for (double x : {0.01, 0.5, 1.0, 3.0, 10.0, 40.0}) {
        EXPECT_NEAR(chi2_p_value(x, 2), std::exp(-0.5 * x), 1e-13 + 1e-12 * std::exp(-0.5 * x));
        const double ref1 = std::erfc(std::sqrt(0.5 * x));
        EXPECT_NEAR(chi2_p_value(x, 1), ref1, 1e-12 + 1e-10 * ref1);
    }
    // dof = 4: P(X > x) = exp(-x/2) (1 + x/2).
    for (double x : {0.3, 2.0, 7.0, 25.0})
        EXPECT_NEAR(chi2_p_value(x, 4), std::exp(-0.5 * x) * (1 + 0.5 * x), 1e-12);
    // Tabulated quantiles: 95th percentile of chi2_10 is 18.307, 99th of chi2_100 is 135.807.
    EXPECT_NEAR(chi2_p_value(18.307038, 10), 0.05, 1e-7);
    EXPECT_NEAR(chi2_p_value(135.80672, 100), 0.01, 1e-7);
}

TEST(Chi2Harness, QuadratureOfKnownIntegrals) {
    // Smooth: integral of cos(x) sin(y) over [0, pi/2]^2 = 1.
    EXPECT_NEAR(integrate_2d([](double x, double y) { return std::cos(x) * std::sin(y); }, 0,
                             kPi / 2, 0, kPi / 2, 1e-10),
                1.0, 1e-9);
    // Discontinuous: the unit quarter disk has area pi / 4.
    EXPECT_NEAR(integrate_2d([](double x, double y) { return x * x + y * y <= 1 ? 1.0 : 0.0; }, 0,
                             1, 0, 1, 1e-7),
                kPi / 4, 1e-5);
}

TEST(Chi2Harness, RejectsSlightlyWrongDensity) {
    // Cosine-distributed samples tested against the normalised density (n + 1) cos^n / (2 pi)
    // with n = 1.1 instead of 1: a 10% change of the exponent must be rejected decisively.
    const double n = 1.1;
    const Chi2Result r = direction_test(
        femto::warp::square_to_cosine_hemisphere,
        [&](const Vec3& v) {
            return v.z > 0 ? (n + 1) * std::pow(double(v.z), n) / (2 * kPi) : 0.0;
        },
        "wrong density");
    std::printf("[chi2] wrong density: %s\n", r.describe().c_str());
    EXPECT_LT(r.p_value, 1e-6) << r.describe();
}

}  // namespace
