// Tests of the phase function plugins (isotropic, hg): chi-square goodness of fit of sample()
// against eval() over the whole sphere (tests/unit/chi2.h), normalisation and mean cosine of
// eval() by quadrature, the mean cosine of samples, and parameter validation.
//
// Convention (femto/medium.h): wi points back toward the previous vertex, so the scattering
// angle's cosine is dot(-wi, wo) and Henyey-Greenstein's mean cosine is g.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "chi2.h"
#include "femto/error.h"
#include "femto/host.h"
#include "femto/medium.h"

namespace {

using femto::PhaseFunction;
using femto::PluginKind;
using femto::Properties;
using femto::Vec3;
using namespace femto_test;

std::shared_ptr<PhaseFunction> make_phase(const std::string& type, std::optional<double> g = {}) {
    Properties props(type, {});
    if (g) props.set_float("g", *g);
    femto::ObjectPtr obj = femto::create_object(PluginKind::Phase, type, props);
    EXPECT_TRUE(obj);
    EXPECT_EQ(obj->kind(), PluginKind::Phase);
    return std::static_pointer_cast<PhaseFunction>(obj);
}

double dot_d(const Vec3& a, const Vec3& b) {
    return double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z;
}

/// The incident directions tried: along +z (the forward peak of -wi sits on a pole of the
/// (cos theta, phi) chart), and two oblique ones (the peak is off the chart's axes).
std::vector<std::pair<std::string, Vec3>> incident_directions() {
    return {{"wi_z", Vec3(0, 0, 1)},
            {"wi_50deg", direction_deg(50.0, 0.7)},
            {"wi_120deg", direction_deg(120.0, 4.0)}};
}

struct PhaseCase {
    std::string name;
    std::string type;
    std::optional<double> g;
    Vec3 wi;
    double mean_cosine() const { return g.value_or(0.0); }
};

void PrintTo(const PhaseCase& c, std::ostream* os) { *os << c.name; }

std::string g_name(double g) {
    std::string s = std::to_string(g);
    s.erase(s.find_last_not_of('0') + 1);
    for (char& c : s)
        if (c == '.') c = 'p';
    if (s[0] == '-') s = "m" + s.substr(1);
    return s;
}

std::vector<PhaseCase> make_cases() {
    std::vector<PhaseCase> cases;
    for (const auto& [wname, wi] : incident_directions())
        cases.push_back({"isotropic_" + wname, "isotropic", std::nullopt, wi});
    for (double g : {-0.9, -0.5, 0.3, 0.8, 0.95})
        for (const auto& [wname, wi] : incident_directions())
            cases.push_back({"hg_g" + g_name(g) + "_" + wname, "hg", g, wi});
    // Near and at g = 0, where the textbook inverse CDF cancels catastrophically.
    cases.push_back({"hg_g0_wi_50deg", "hg", 0.0, direction_deg(50.0, 0.7)});
    cases.push_back({"hg_g1em4_wi_50deg", "hg", 1e-4, direction_deg(50.0, 0.7)});
    cases.push_back({"hg_gm1em6_wi_120deg", "hg", -1e-6, direction_deg(120.0, 4.0)});
    return cases;
}

const std::vector<PhaseCase>& all_cases() {
    static const std::vector<PhaseCase> cases = make_cases();
    return cases;
}

class PhaseTest : public ::testing::TestWithParam<PhaseCase> {};

TEST_P(PhaseTest, SampleMatchesEvalChiSquare) {
    const PhaseCase& c = GetParam();
    auto phase = make_phase(c.type, c.g);
    ASSERT_TRUE(phase);
    Chi2Options opt;  // (cos theta, phi) over the whole sphere: dw = dcos dphi
    opt.seed = seed_from_name(c.name);
    size_t bad = 0;
    auto sample = [&](femto::Pcg32& rng) -> std::optional<std::pair<double, double>> {
        const femto::Vec2 u(rng.next_float(), rng.next_float());
        const Vec3 wo = phase->sample(c.wi, u);
        if (!femto::is_finite(wo) || std::abs(femto::length(wo) - 1.f) > 1e-5f) ++bad;
        return sphere_coords(wo);
    };
    auto pdf = [&](double cos_theta, double phi) {
        return double(phase->eval(c.wi, sphere_direction(cos_theta, phi)));
    };
    const Chi2Result r = chi2_test(opt, sample, pdf);
    const double alpha = corrected_significance(static_cast<int>(all_cases().size()));
    EXPECT_EQ(bad, 0u) << "non-unit or non-finite sampled directions";
    EXPECT_TRUE(r.error.empty()) << r.describe();
    EXPECT_EQ(r.histogrammed, r.samples) << "a phase function always returns a direction";
    EXPECT_GT(r.p_value, alpha) << r.describe();
    // The per-bin quadrature asks for max(1e-9, 1e-5 m) per bin of mass m: at most
    // 8192e-9 + 1e-5 over the sphere.
    EXPECT_NEAR(r.pdf_integral, 1.0,
                opt.nx * opt.ny * opt.integration_abs_eps + opt.integration_rel_eps)
        << r.describe();
}

/// Integral over the sphere of f(direction) by adaptive Simpson quadrature over a 32 x 64
/// grid of world (cos theta, phi) cells, with the tolerance the quadrature was asked for: the
/// sum of every cell's max(abs_eps, rel_eps * |cell|).
struct Quadrature {
    double value = 0, tolerance = 0;
};
template <typename F>
Quadrature sphere_integral(const F& f, double abs_eps = 1e-10, double rel_eps = 1e-6) {
    constexpr int kNx = 32, kNy = 64;
    Quadrature q;
    const double wx = 2.0 / kNx, wy = 2 * kPi / kNy;
    auto g = [&](double cos_theta, double phi) { return f(sphere_direction(cos_theta, phi)); };
    for (int i = 0; i < kNx; ++i)
        for (int j = 0; j < kNy; ++j) {
            const double x0 = -1.0 + i * wx, y0 = j * wy;
            const double cell = integrate_2d(g, x0, x0 + wx, y0, y0 + wy, abs_eps, rel_eps);
            q.value += cell;
            q.tolerance += std::max(abs_eps, rel_eps * std::abs(cell));
        }
    return q;
}

TEST_P(PhaseTest, EvalIntegratesToOneWithMeanCosineG) {
    const PhaseCase& c = GetParam();
    auto phase = make_phase(c.type, c.g);
    ASSERT_TRUE(phase);
    const Quadrature norm = sphere_integral([&](const Vec3& wo) { return phase->eval(c.wi, wo); });
    const Quadrature mean =
        sphere_integral([&](const Vec3& wo) { return phase->eval(c.wi, wo) * dot_d(-c.wi, wo); });
    // Besides the quadrature's tolerance (times 4 for the slack of its Richardson error
    // estimate), the integrand is only known at float directions: rounding wo to float moves
    // the scattering cosine by up to ~2^-24, which moves the integral by at most
    // 2^-24 * (integral of |dp/dcos| over the sphere) = 2^-24 * 2 pi (p_max - p_min) for a p
    // monotonic in the cosine (2^-23 here for margin); and eval() rounds its value to float.
    const double p_max = phase->eval(c.wi, -c.wi), p_min = phase->eval(c.wi, c.wi);
    const double direction_rounding = 0x1p-23 * 2 * kPi * std::abs(p_max - p_min);
    const double value_rounding = 0x1p-23;
    EXPECT_NEAR(norm.value, 1.0, 4 * norm.tolerance + direction_rounding + value_rounding)
        << "quadrature tolerance " << norm.tolerance << ", direction rounding "
        << direction_rounding;
    EXPECT_NEAR(mean.value, c.mean_cosine(),
                4 * mean.tolerance + direction_rounding + value_rounding)
        << "quadrature tolerance " << mean.tolerance << ", direction rounding "
        << direction_rounding;
}

TEST_P(PhaseTest, SampleMeanCosineIsG) {
    const PhaseCase& c = GetParam();
    auto phase = make_phase(c.type, c.g);
    ASSERT_TRUE(phase);
    femto::Pcg32 rng(seed_from_name(c.name + "mean"), 7);
    constexpr int kN = 1000000;
    double sum = 0, sum2 = 0;
    for (int i = 0; i < kN; ++i) {
        const Vec3 wo = phase->sample(c.wi, {rng.next_float(), rng.next_float()});
        const double cs = dot_d(-c.wi, wo);
        sum += cs;
        sum2 += cs * cs;
    }
    const double mean = sum / kN;
    const double var = std::max(0.0, sum2 / kN - mean * mean);
    const double se = std::sqrt(var / (kN - 1));
    EXPECT_NEAR(mean, c.mean_cosine(), 4 * se) << "standard error " << se;
}

INSTANTIATE_TEST_SUITE_P(Phase, PhaseTest, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<PhaseCase>& info) {
                             return info.param.name;
                         });

TEST(PhaseIsotropic, ConstantValue) {
    auto iso = make_phase("isotropic");
    const float expected = 1.f / (4.f * femto::kPi);
    for (const auto& [name, wi] : incident_directions())
        for (double t : {0.0, 33.0, 90.0, 151.0, 180.0})
            EXPECT_FLOAT_EQ(iso->eval(wi, direction_deg(t, 1.3)), expected) << name << " " << t;
}

TEST(PhaseHg, DefaultIsIsotropicAndValuesMatchTheFormula) {
    auto hg0 = make_phase("hg");  // g defaults to 0
    const Vec3 wi = direction_deg(50.0, 0.7);
    for (double t : {0.0, 45.0, 90.0, 170.0})
        EXPECT_FLOAT_EQ(hg0->eval(wi, direction_deg(t, 2.0)), 1.f / (4.f * femto::kPi));

    for (double g : {-0.7, 0.2, 0.9}) {
        auto hg = make_phase("hg", g);
        for (double t : {0.0, 20.0, 90.0, 140.0, 180.0}) {
            // wi = +z: the scattering cosine dot(-wi, wo) is -cos(t) for wo at polar angle t.
            const double cs = -std::cos(t * kPi / 180.0);
            const double expected = (1 - g * g) / (4 * kPi * std::pow(1 + g * g - 2 * g * cs, 1.5));
            EXPECT_NEAR(hg->eval(Vec3(0, 0, 1), direction_deg(t, 0.3)), expected, 1e-6 * expected)
                << "g " << g << " t " << t;
        }
        // Forward scattering for g > 0: wo = -wi is the most likely direction.
        const float forward = hg->eval(wi, -wi), backward = hg->eval(wi, wi);
        if (g > 0) {
            EXPECT_GT(forward, backward);
        } else {
            EXPECT_LT(forward, backward);
        }
    }
}

TEST(PhaseHg, Reciprocal) {
    auto hg = make_phase("hg", 0.6);
    femto::Pcg32 rng(3, 5);
    for (int i = 0; i < 100; ++i) {
        const Vec3 a = sphere_direction(2 * rng.next_double() - 1, 2 * kPi * rng.next_double());
        const Vec3 b = sphere_direction(2 * rng.next_double() - 1, 2 * kPi * rng.next_double());
        EXPECT_NEAR(hg->eval(a, b), hg->eval(-b, -a), 1e-6 * hg->eval(a, b));
    }
}

TEST(PhaseHg, ExtremeUniformsGiveUnitDirections) {
    for (double g : {-0.999, -0.5, 0.0, 1e-7, 0.5, 0.999}) {
        auto hg = make_phase("hg", g);
        for (float ux : {0.f, 1e-7f, 0.5f, 1.f - 0x1p-24f, 1.f})
            for (float uy : {0.f, 0.5f, 1.f - 0x1p-24f}) {
                const Vec3 wo = hg->sample(direction_deg(50.0, 0.7), {ux, uy});
                EXPECT_TRUE(femto::is_finite(wo)) << g << " " << ux << " " << uy;
                EXPECT_NEAR(femto::length(wo), 1.f, 1e-5f) << g << " " << ux << " " << uy;
            }
    }
}

TEST(PhaseHg, RejectsGOutsideTheOpenInterval) {
    const femto::SourceLocation loc{"scene.xml", 7, 9};
    for (double g : {1.0, -1.0, 1.5, -3.0, std::numeric_limits<double>::quiet_NaN(),
                     std::numeric_limits<double>::infinity()}) {
        Properties props("hg", {"scene.xml", 6, 5});
        props.set("g", Properties::Type::Float, g, loc);
        try {
            femto::create_object(PluginKind::Phase, "hg", props);
            ADD_FAILURE() << "g = " << g << " was accepted";
        } catch (const femto::SceneError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("scene.xml:7:9"), std::string::npos) << what;
            EXPECT_NE(what.find("g"), std::string::npos) << what;
            if (std::isfinite(g)) {
                EXPECT_NE(what.find("(-1, 1)"), std::string::npos) << what;
            }
        }
    }
}

TEST(PhaseSchema, Listed) {
    const femto::PluginDescriptor& iso = femto::find_plugin(PluginKind::Phase, "isotropic");
    EXPECT_EQ(iso.kind, PluginKind::Phase);
    EXPECT_TRUE(iso.params.empty());
    const femto::PluginDescriptor& hg = femto::find_plugin(PluginKind::Phase, "hg");
    ASSERT_EQ(hg.params.size(), 1u);
    EXPECT_EQ(std::string(hg.params[0].name), "g");
    // An unknown parameter is an error, as for every plugin.
    Properties props("hg", {});
    props.set_float("gg", 0.5);
    EXPECT_THROW(femto::create_object(PluginKind::Phase, "hg", props), femto::SceneError);
}

}  // namespace
