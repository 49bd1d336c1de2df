// Chi-square tests of every non-delta BSDF sampling routine against its pdf() (as Mitsuba's
// test suite): 1e6 sample() directions histogrammed over (cos theta, phi) in 64 x 128 bins,
// expected counts from integrating pdf() over every bin (adaptive Simpson), sparse bins
// pooled. A case fails when its p-value is below the Šidák-corrected level for 1% over all
// cases in this file. Delta lobes (plastic's coating) are conditioned away: their samples
// are not histogrammed and pdf() excludes them, so pdf() integrates to the probability of a
// non-delta sample, which is checked against the observed fraction.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "btf/synth.h"
#include "btf_test_util.h"
#include "chi2.h"
#include "femto/bsdf.h"
#include "femto/properties.h"
#include "femto/testing/render.h"

namespace {

using femto::Bsdf;
using femto::Properties;
using femto::Vec3;
using namespace femto_test;

struct BsdfChi2Case {
    std::string name;
    std::function<Properties()> props;
    double theta_deg;  ///< polar angle of wi (> 90: arriving from below)
    double phi = 0.7;  ///< azimuth of wi (not 0, so anisotropy is seen at an angle)
    std::vector<Properties> children = {};  ///< nested BSDFs (twosided)
};

// gtest prints a parameter into the ctest name: print the case name (not the struct's bytes).
void PrintTo(const BsdfChi2Case& c, std::ostream* os) { *os << c.name; }

std::string angle_name(double deg) { return std::to_string(static_cast<int>(deg)) + "deg"; }

// A small synthetic BTF (BTF A, docs/btf.md), written once per process.
std::string synthetic_btf_file() {
    static const std::string path =
        femto::test::write_btf(femto::test::small_btf_a(), "chi2-btf", "a.dfmf");
    return path;
}

std::vector<BsdfChi2Case> make_cases() {
    std::vector<BsdfChi2Case> cases;
    const double angles[] = {0.0, 45.0, 80.0};

    for (double a : angles)
        cases.push_back({"diffuse_" + angle_name(a),
                         [] {
                             Properties p("diffuse", {});
                             p.set_color("reflectance", femto::Color(0.3f, 0.6f, 0.9f));
                             return p;
                         },
                         a});

    struct Rough {
        const char* name;
        double au, av;  // av < 0: isotropic `alpha`
    };
    const Rough roughness[] = {
        {"a0p1", 0.1, -1}, {"a0p3", 0.3, -1}, {"a0p8", 0.8, -1}, {"aniso_0p15_0p5", 0.15, 0.5}};
    for (const char* dist : {"beckmann", "ggx"})
        for (const Rough& r : roughness)
            for (bool visible : {true, false})
                for (double a : angles) {
                    const std::string name = std::string("roughconductor_") + dist + "_" + r.name +
                                             (visible ? "_visible_" : "_full_") + angle_name(a);
                    cases.push_back({name,
                                     [=] {
                                         Properties p("roughconductor", {});
                                         p.set_string("distribution", dist);
                                         if (r.av < 0) {
                                             p.set_float("alpha", r.au);
                                         } else {
                                             p.set_float("alpha_u", r.au);
                                             p.set_float("alpha_v", r.av);
                                         }
                                         p.set_bool("sample_visible", visible);
                                         p.set_string("material", "Au");
                                         return p;
                                     },
                                     a});
                }

    // Plastic: the diffuse part, conditioned on non-delta samples.
    for (double a : angles)
        cases.push_back({"plastic_" + angle_name(a),
                         [] {
                             Properties p("plastic", {});
                             p.set_color("diffuse_reflectance", femto::Color(0.2f, 0.5f, 0.8f));
                             return p;
                         },
                         a});
    cases.push_back({"plastic_diamond_nonlinear_60deg",
                     [] {
                         Properties p("plastic", {});
                         p.set_string("int_ior", "diamond");
                         p.set_bool("nonlinear", true);
                         p.set_float("diffuse_reflectance", 0.9);
                         return p;
                     },
                     60.0});

    // roughplastic: both lobes (glossy coating and diffuse base) are non-delta.
    for (const char* dist : {"beckmann", "ggx"})
        for (double alpha : {0.05, 0.3})
            for (double a : angles) {
                const std::string name = std::string("roughplastic_") + dist +
                                         (alpha < 0.1 ? "_a0p05_" : "_a0p3_") + angle_name(a);
                cases.push_back({name,
                                 [=] {
                                     Properties p("roughplastic", {});
                                     p.set_string("distribution", dist);
                                     p.set_float("alpha", alpha);
                                     p.set_color("diffuse_reflectance",
                                                 femto::Color(0.2f, 0.5f, 0.8f));
                                     return p;
                                 },
                                 a});
            }
    for (const char* dist : {"beckmann", "ggx"})
        cases.push_back({std::string("roughplastic_") + dist + "_a0p2_full_nonlinear_60deg",
                         [=] {
                             Properties p("roughplastic", {});
                             p.set_string("distribution", dist);
                             p.set_float("alpha", 0.2);
                             p.set_bool("sample_visible", false);
                             p.set_bool("nonlinear", true);
                             p.set_string("int_ior", "diamond");
                             p.set_float("diffuse_reflectance", 0.9);
                             return p;
                         },
                         60.0});

    // twosided: the back side, one nested BSDF and two.
    auto diffuse = [] {
        Properties p("diffuse", {});
        p.set_float("reflectance", 0.8);
        return p;
    };
    auto rough = [](const char* dist) {
        Properties p("roughconductor", {});
        p.set_string("distribution", dist);
        p.set_float("alpha", 0.3);
        return p;
    };
    cases.push_back({"twosided_diffuse_back_135deg",
                     [] { return Properties("twosided", {}); },
                     135.0,
                     0.7,
                     {diffuse()}});
    cases.push_back({"twosided_ggx_back_120deg",
                     [] { return Properties("twosided", {}); },
                     120.0,
                     0.7,
                     {rough("ggx")}});
    cases.push_back({"twosided_front_diffuse_back_beckmann_150deg",
                     [] { return Properties("twosided", {}); },
                     150.0,
                     0.7,
                     {diffuse(), rough("beckmann")}});
    cases.push_back({"twosided_front_diffuse_back_beckmann_30deg",
                     [] { return Properties("twosided", {}); },
                     30.0,
                     0.7,
                     {diffuse(), rough("beckmann")}});
    // mask: the nested lobes with probability `opacity` (pdf() integrates to it), the rest a
    // delta pass-through that is conditioned away.
    auto mask = [](double opacity) {
        return [=] {
            Properties p("mask", {});
            p.set_float("opacity", opacity);
            return p;
        };
    };
    cases.push_back({"mask_diffuse_45deg", mask(0.35), 45.0, 0.7, {diffuse()}});
    cases.push_back({"mask_ggx_30deg", mask(0.6), 30.0, 0.7, {rough("ggx")}});
    cases.push_back({"btf_synthetic_40deg",
                     [] {
                         Properties p("btf", {});
                         p.set_string("filename", synthetic_btf_file());
                         return p;
                     },
                     40.0});
    return cases;
}

const std::vector<BsdfChi2Case>& all_cases() {
    static const std::vector<BsdfChi2Case> cases = make_cases();
    return cases;
}

class BsdfChi2 : public ::testing::TestWithParam<BsdfChi2Case> {};

TEST_P(BsdfChi2, SamplesFollowPdf) {
    const BsdfChi2Case& c = GetParam();
    Properties props = c.props();
    for (size_t i = 0; i < c.children.size(); ++i)
        props.set_object("_arg_" + std::to_string(i), make_bsdf(c.children[i]));
    const std::shared_ptr<Bsdf> bsdf = make_bsdf(props);
    ASSERT_TRUE(bsdf);

    const femto::Hit hit;
    const Vec3 wi = direction_deg(c.theta_deg, c.phi);
    Chi2Options opt;  // 64 x 128 bins over (cos theta, phi), 1e6 samples
    opt.seed = seed_from_name(c.name);
    const Chi2Result res = chi2_test(
        opt,
        [&](femto::Pcg32& rng) -> std::optional<std::pair<double, double>> {
            const float u_lobe = rng.next_float();
            const femto::Vec2 u(rng.next_float(), rng.next_float());
            const femto::BsdfSample s = bsdf->sample(hit, wi, u_lobe, u);
            if (!s.valid() || (s.sampled_lobe & femto::kBsdfDelta)) return std::nullopt;
            return sphere_coords(s.wo);
        },
        [&](double cos_theta, double phi) {
            return static_cast<double>(bsdf->pdf(hit, wi, sphere_direction(cos_theta, phi)));
        });

    const double level = corrected_significance(static_cast<int>(all_cases().size()));
    EXPECT_TRUE(res.error.empty()) << res.describe();
    EXPECT_GT(res.p_value, level) << res.describe();
    // pdf() is a (sub-)probability density: its integral is at most one, up to the quadrature
    // tolerance (sum over bins of max(1e-9, 1e-5 m) <= 8192e-9 + 1e-5 < 2e-5; 1e-4 allows 5x).
    EXPECT_LE(res.pdf_integral, 1.0 + 1e-4) << res.describe();
    // ... and equals the probability that sample() returns a non-delta direction: the
    // returned fraction is a binomial proportion with standard error sqrt(q (1 - q) / N);
    // allowed: 4 standard errors plus the quadrature tolerance. For materials whose sampling
    // never fails (diffuse) this says the pdf integrates to one.
    const double q = std::clamp(res.pdf_integral, 0.0, 1.0);
    const double se = std::sqrt(q * (1.0 - q) / static_cast<double>(res.samples));
    EXPECT_NEAR(res.returned_fraction(), res.pdf_integral, 4.0 * se + 1e-4) << res.describe();
    RecordProperty("p_value", std::to_string(res.p_value));
    std::printf("[chi2] %s: %s (level %.3g)\n", c.name.c_str(), res.describe().c_str(), level);
}

// The test's power on a narrow lobe: samples of a Beckmann alpha = 0.1 conductor tested against
// the pdf of alpha = 0.102 (2% rougher) must be rejected decisively.
TEST(BsdfChi2Power, RejectsTwoPercentRoughnessError) {
    auto make = [](double alpha) {
        Properties p("roughconductor", {});
        p.set_float("alpha", alpha);
        return make_bsdf(p);
    };
    const std::shared_ptr<Bsdf> sampled = make(0.1), claimed = make(0.102);
    const femto::Hit hit;
    const Vec3 wi = direction_deg(45.0, 0.7);
    Chi2Options opt;
    opt.seed = seed_from_name("power");
    const Chi2Result res = chi2_test(
        opt,
        [&](femto::Pcg32& rng) -> std::optional<std::pair<double, double>> {
            const float u_lobe = rng.next_float();
            const femto::Vec2 u(rng.next_float(), rng.next_float());
            const femto::BsdfSample s = sampled->sample(hit, wi, u_lobe, u);
            if (!s.valid()) return std::nullopt;
            return sphere_coords(s.wo);
        },
        [&](double cos_theta, double phi) {
            return static_cast<double>(claimed->pdf(hit, wi, sphere_direction(cos_theta, phi)));
        });
    std::printf("[chi2] alpha 0.1 vs 0.102: %s\n", res.describe().c_str());
    EXPECT_LT(res.p_value, 1e-6) << res.describe();
}

INSTANTIATE_TEST_SUITE_P(Bsdf, BsdfChi2, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<BsdfChi2Case>& info) {
                             return info.param.name;
                         });

}  // namespace
