// Synthetic V-groove BTF (btf/vgroove.h): the closed-form period average against the exact
// texel averages, an independent stratified ray caster, and cases with known answers.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "btf/vgroove.h"

namespace femto::btf {
namespace {

constexpr double kDegree = std::numbers::pi / 180;

/// A unit direction with z in (z_min, 1] and uniform azimuth. Stored in float (femto's Vec3);
/// every route reads the same floats, so the comparisons below are not affected by it.
Vec3 random_direction(std::mt19937_64& rng, double z_min = 0.05) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const double z = 1.0 - (1.0 - z_min) * unit(rng);  // in (z_min, 1]
    const double phi = 2 * std::numbers::pi * unit(rng);
    const double r = std::sqrt(1 - z * z);
    return {static_cast<float>(r * std::cos(phi)), static_cast<float>(r * std::sin(phi)),
            static_cast<float>(z)};
}

VGroove random_groove(std::mt19937_64& rng) {
    std::uniform_real_distribution<double> angle(5 * kDegree, 80 * kDegree), albedo(0.1, 1.0);
    return {angle(rng), albedo(rng)};
}

double mean(const std::vector<double>& values) {
    double sum = 0;
    for (double x : values) sum += x;
    return sum / static_cast<double>(values.size());
}

/// Largest value B can take: rho n_f.l / l.z <= rho / l.z. Tolerances scale with it.
double reflectance_scale(const VGroove& g, const Vec3& l) { return g.albedo / l.z; }

// ---- An independent ray caster ----------------------------------------------------------
// It uses a different argument from the library's segment casting: the groove of period m,
// {z > tan g (|x - m - 1/2| - 1/2), z < 0}, is convex (the intersection of the half-planes
// above the two facet lines and below z = 0). A ray starting inside it leaves it exactly
// once: the view ray through the first facet line it crosses, and a ray from a facet point
// toward l is unshadowed iff it leaves through the opening z = 0, x in [m, m+1].

struct BruteHit {
    Facet facet;
    double x, z;
};

BruteHit brute_view_hit(const VGroove& g, double x, const Vec3& v) {
    const double t = std::tan(g.slope_angle), m = std::floor(x);
    // Ray (x - s v.x, -s v.z), s > 0, against z = -(X - m) t and z = (X - m - 1) t.
    const double to_left = v.z + v.x * t, to_right = v.z - v.x * t;  // sum 2 v.z > 0
    const double s_left = to_left > 0 ? (x - m) * t / to_left : INFINITY;
    const double s_right = to_right > 0 ? (m + 1 - x) * t / to_right : INFINITY;
    const double s = std::min(s_left, s_right);
    return {s_left <= s_right ? Facet::Left : Facet::Right, x - s * v.x, -s * v.z};
}

double brute_reflectance(const VGroove& g, double x, const Vec3& l, const Vec3& v) {
    const BruteHit hit = brute_view_hit(g, x, v);
    const double sign = hit.facet == Facet::Left ? 1.0 : -1.0;
    const double n_dot_l = sign * std::sin(g.slope_angle) * l.x + std::cos(g.slope_angle) * l.z;
    if (n_dot_l <= 0) return 0;
    const double m = std::floor(x);
    const double exit_x = hit.x - hit.z * l.x / l.z;
    const bool lit = exit_x >= m && exit_x <= m + 1;
    return lit ? g.albedo * n_dot_l / l.z : 0.0;
}

struct StratifiedEstimate {
    double mean_reflectance;
    double left_fraction;  // fraction of view rays that hit the left facet
};

/// One jittered sample in each of N equal strata of [x0, x1].
StratifiedEstimate stratified(const VGroove& g, double x0, double x1, const Vec3& l, const Vec3& v,
                              int N, std::mt19937_64& rng) {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    double sum = 0, left = 0;
    for (int i = 0; i < N; ++i) {
        const double x = x0 + (x1 - x0) * (i + unit(rng)) / N;
        sum += brute_reflectance(g, x, l, v);
        left += brute_view_hit(g, x, v).facet == Facet::Left ? 1 : 0;
    }
    return {sum / N, left / N};
}

// ---- 1. Masking normalisation ----------------------------------------------------------

TEST(VGroove, VisibleProjectedWidthsSumToOne) {
    std::mt19937_64 rng(1);
    for (int trial = 0; trial < 10000; ++trial) {
        const VGroove g = random_groove(rng);
        const Vec3 v = random_direction(rng, 0.01);
        const double total = vgroove_projected_width(g, Facet::Left, v) +
                             vgroove_projected_width(g, Facet::Right, v);
        // A handful of roundings of O(1) terms (the ratio form is exactly 1 in reals).
        EXPECT_NEAR(total, 1.0, 1e-12) << "g=" << g.slope_angle << " v=" << v.x << "," << v.z;
    }
}

// ---- 2. Texels against the closed form ---------------------------------------------------

TEST(VGroove, TexelMeanEqualsClosedForm) {
    std::mt19937_64 rng(2);
    for (int trial = 0; trial < 2000; ++trial) {
        const VGroove g = random_groove(rng);
        const Vec3 l = random_direction(rng), v = random_direction(rng);
        const double closed = vgroove_period_average(g, l, v);
        for (int W : {1, 7, 64}) {
            // Both routes are exact; they differ by rounding only: the break positions carry
            // an error of a few ulps of |d v.x / v.z| <= 57 (g < 80 deg, v.z > 0.05), which
            // moves area of height <= rho / l.z, so the tolerance is relative to that scale
            // (the worst case seen is 1.6e-15 of it, 3.7e-14 of the value itself).
            EXPECT_NEAR(mean(vgroove_texels(g, W, l, v)), closed, 1e-12 * reflectance_scale(g, l))
                << "W=" << W << " g=" << g.slope_angle << " l=" << l.x << "," << l.y << "," << l.z
                << " v=" << v.x << "," << v.y << "," << v.z;
        }
    }
}

// ---- 3. Independent brute force ------------------------------------------------------------

struct Configuration {
    VGroove groove;
    Vec3 l, v;
};

Vec3 unit_vector(double x, double y, double z) {
    const double r = std::sqrt(x * x + y * y + z * z);
    return {static_cast<float>(x / r), static_cast<float>(y / r), static_cast<float>(z / r)};
}

/// Hand-picked cases where B really varies, then random ones (which often see one facet only
/// and light it entirely, leaving B constant).
std::vector<Configuration> brute_force_configurations() {
    std::vector<Configuration> out = {
        // Right facet faces away from l, left facet partly shadowed, both facets visible.
        {{45 * kDegree, 0.9}, unit_vector(0.8, 0.1, 0.59), unit_vector(-0.3, 0.2, 0.93)},
        // The mirror case, steeper grooves.
        {{60 * kDegree, 0.6}, unit_vector(-0.5, -0.3, 0.81), unit_vector(0.4, 0.5, 0.77)},
        // Everything visible and lit: B takes one value per facet.
        {{30 * kDegree, 1.0}, unit_vector(0.3, 0.0, 0.95), unit_vector(0.2, -0.2, 0.96)},
        // Steep grooves, view and light from the same side: only the left facet is visible
        // (its top 53 %) and only its top 22 % is lit.
        {{70 * kDegree, 0.5}, unit_vector(0.9, 0.2, 0.3), unit_vector(0.5, 0.1, 0.5)},
    };
    std::mt19937_64 rng(3);
    for (int trial = 0; trial < 4; ++trial) {
        const VGroove g = random_groove(rng);
        const Vec3 l = random_direction(rng), v = random_direction(rng);
        out.push_back({g, l, v});
    }
    return out;
}

TEST(VGroove, AverageMatchesStratifiedRayCasting) {
    std::mt19937_64 rng(33);
    constexpr int N = 1'000'000;
    const double intervals[][2] = {{0.0, 1.0}, {0.13, 0.61}, {-0.7, 2.35}};
    for (const auto& [g, l, v] : brute_force_configurations()) {
        for (const auto& interval : intervals) {
            const double x0 = interval[0], x1 = interval[1];
            const StratifiedEstimate brute = stratified(g, x0, x1, l, v, N, rng);
            // B is piecewise constant with <= 3 jumps per period (rim, bottom vertex, shadow
            // edge), each of height <= rho / l.z. Only strata containing a jump are estimated
            // with an error, of at most its height times 1/N of the mean: the bound is
            // deterministic, K rho / (l.z N) with K = 3 per period touched.
            const double periods = std::floor(x1) - std::floor(x0) + 1;
            const double tolerance = 3 * periods * reflectance_scale(g, l) / N + 1e-12;
            EXPECT_NEAR(vgroove_average(g, x0, x1, l, v), brute.mean_reflectance, tolerance)
                << "g=" << g.slope_angle << " [" << x0 << "," << x1 << "]";
            if (x0 == 0.0 && x1 == 1.0) {
                // Which facet is hit jumps at the rim and the bottom vertex's projection.
                EXPECT_NEAR(vgroove_projected_width(g, Facet::Left, v), brute.left_fraction,
                            2.0 / N + 1e-12);
            }
        }
    }
}

// ---- 4. Cases with known answers -----------------------------------------------------------

TEST(VGroove, NormalIncidenceGivesRhoCosSlope) {
    // l = v = z: both facets are fully visible and lit, each point shows n_f.z = cos g, so
    // B = rho cos g everywhere (closed form: rho * 2 * cos g * L * cos g = rho cos g).
    const Vec3 z{0, 0, 1};
    for (double degrees : {5.0, 30.0, 45.0, 80.0}) {
        const VGroove g{degrees * kDegree, 0.8};
        const double expected = g.albedo * std::cos(g.slope_angle);
        EXPECT_NEAR(vgroove_period_average(g, z, z), expected, 1e-15);
        for (double texel : vgroove_texels(g, 16, z, z)) EXPECT_NEAR(texel, expected, 1e-15);
    }
}

TEST(VGroove, NearlyFlatGrooveIsLambertian) {
    // n_f.l / l.z = cos g +- sin g l.x / l.z and no shadowing unless |l.x| / l.z > cot g
    // (never for l.z > 0.05 and g = 1e-6), so every B is within
    // rho (g^2 / 2 + g |l.x| / l.z) of rho, and so is their mean.
    std::mt19937_64 rng(4);
    const VGroove g{1e-6, 0.7};
    for (int trial = 0; trial < 1000; ++trial) {
        const Vec3 l = random_direction(rng), v = random_direction(rng);
        const double tolerance =
            g.albedo * (g.slope_angle * g.slope_angle / 2 + g.slope_angle * std::abs(l.x) / l.z) +
            1e-14;
        EXPECT_NEAR(vgroove_period_average(g, l, v), g.albedo, tolerance);
        for (double texel : vgroove_texels(g, 8, l, v)) EXPECT_NEAR(texel, g.albedo, tolerance);
    }
}

TEST(VGroove, GrazingSideLightShadowsOneFacet) {
    // g = 45 deg and light from +x at projected angle phi = atan(3) > 45 deg: the right
    // facet faces away from it (attached shadow, contributes 0) and the left facet is lit
    // on its top fraction a = 2 cos g cos phi / cos(phi - g). Seen from v = z, the left
    // facet covers x in [0, 1/2) with its top at x = 0, the right one [1/2, 1).
    const VGroove g{45 * kDegree, 0.9};
    const Vec3 l{0.9f / std::sqrt(0.91f), 0.1f / std::sqrt(0.91f), 0.3f / std::sqrt(0.91f)};
    const Vec3 v{0, 0, 1};
    ASSERT_EQ(vgroove_visible_fraction(g, Facet::Right, l), 0.0);
    const double lx = l.x, lz = l.z;  // in double: std::atan2(float, float) is a float
    const double phi = std::atan2(lx, lz), c = std::cos(g.slope_angle);
    const double lit = 2 * c * std::cos(phi) / std::cos(phi - g.slope_angle);
    EXPECT_NEAR(vgroove_visible_fraction(g, Facet::Left, l), lit, 1e-15);
    const double n_dot_l = std::sin(g.slope_angle) * lx + c * lz;
    const double lit_value = g.albedo * n_dot_l / lz;
    // Exact averages over exact pieces: only roundings of O(1) numbers.
    EXPECT_NEAR(vgroove_average(g, 0.5, 1.0, l, v), 0.0, 1e-15);
    EXPECT_NEAR(vgroove_average(g, 0.0, lit / 2, l, v), lit_value, 1e-13);
    EXPECT_NEAR(vgroove_average(g, lit / 2, 0.5, l, v), 0.0, 1e-13);
    EXPECT_NEAR(vgroove_period_average(g, l, v), lit_value * lit / 2, 1e-13);
    EXPECT_NEAR(mean(vgroove_texels(g, 64, l, v)), lit_value * lit / 2, 1e-13);
}

// ---- 5. Periodicity ------------------------------------------------------------------------

TEST(VGroove, AverageIsPeriodic) {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> start(-3.0, 3.0), length(1e-3, 2.5);
    for (int trial = 0; trial < 2000; ++trial) {
        const VGroove g = random_groove(rng);
        const Vec3 l = random_direction(rng), v = random_direction(rng);
        const double x0 = start(rng), x1 = x0 + length(rng);
        // The shift by 1 rounds x0 and x1 (|x| < 8: by <= 4 eps each), which moves area of
        // height <= rho / l.z in or out of an interval of length x1 - x0; plus the rounding
        // of the sums themselves (worst seen: 1.5e-15 of the scale).
        const double tolerance = (16 * DBL_EPSILON / (x1 - x0) + 1e-13) * reflectance_scale(g, l);
        EXPECT_NEAR(vgroove_average(g, x0 + 1, x1 + 1, l, v), vgroove_average(g, x0, x1, l, v),
                    tolerance);
    }
}

// ---- 6. Reciprocity ------------------------------------------------------------------------

TEST(VGroove, PeriodAverageIsReciprocal) {
    // B_avg = rho / (l.z v.z) sum_f L max(0, n_f.l) max(0, n_f.v) min(a_v,f, a_l,f) is
    // symmetric in l and v (pi times a reciprocal apparent BRDF). B_avg l.z is therefore
    // not, unless l.z = v.z. The ray-cast texels check the symmetry independently of the
    // closed form.
    std::mt19937_64 rng(6);
    for (int trial = 0; trial < 2000; ++trial) {
        const VGroove g = random_groove(rng);
        const Vec3 l = random_direction(rng), v = random_direction(rng);
        const double scale = std::max(reflectance_scale(g, l), reflectance_scale(g, v));
        EXPECT_NEAR(vgroove_period_average(g, l, v), vgroove_period_average(g, v, l),
                    1e-13 * scale);
        EXPECT_NEAR(mean(vgroove_texels(g, 7, l, v)), mean(vgroove_texels(g, 7, v, l)),
                    1e-12 * scale);
    }
    const VGroove g{40 * kDegree, 1.0};
    const Vec3 steep{0.1f, 0.0f, std::sqrt(0.99f)}, shallow{-0.6f, 0.0f, 0.8f};
    EXPECT_GT(std::abs(vgroove_period_average(g, steep, shallow) * steep.z -
                       vgroove_period_average(g, shallow, steep) * shallow.z),
              0.1);
}

TEST(VGroove, RejectsInvalidInput) {
    const Vec3 z{0, 0, 1}, below{0, 0, -1};
    EXPECT_THROW(vgroove_texels({0.0, 1.0}, 4, z, z), std::invalid_argument);
    EXPECT_THROW(vgroove_texels({std::numbers::pi / 2, 1.0}, 4, z, z), std::invalid_argument);
    EXPECT_THROW(vgroove_texels({0.5, 1.0}, 0, z, z), std::invalid_argument);
    EXPECT_THROW(vgroove_period_average({0.5, 1.0}, z, below), std::invalid_argument);
    EXPECT_EQ(vgroove_period_average({0.5, 1.0}, below, z), 0.0);
    EXPECT_EQ(mean(vgroove_texels({0.5, 1.0}, 4, below, z)), 0.0);
}

}  // namespace
}  // namespace femto::btf
