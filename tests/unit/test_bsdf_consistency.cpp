// Consistency and physics tests of the material plugins (plugins/bsdfs/*), built through the
// plugin host as a scene would build them.
//
// Tolerances:
//  - Monte Carlo estimates (furnace means, reflected fractions) are compared within k standard
//    errors of the estimate (k = 3 for one-sided "<=" bounds, 4 for two-sided equalities), the
//    standard error being estimated from the samples themselves (or the binomial formula). A
//    floor of 1e-6 covers float rounding when every sample has the same weight (zero spread):
//    each weight is a float with relative rounding < 1e-6 after a few operations.
//  - Deterministic comparisons of two float code paths for the same quantity (sample() vs
//    eval()/pdf(), f(wi, wo) vs f(wo, wi), the plugin's Fresnel term vs a double-precision
//    reference) allow the relative error stated at each test, derived from float rounding
//    over the operations involved (and its conditioning, where a test says so), and far
//    below any modelling error (a missing factor is O(1)).
//  - Quadrature (adaptive Simpson from chi2.h) is run to a tolerance stated where it is used.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <functional>
#include <memory>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "chi2.h"
#include "femto/bsdf.h"
#include "femto/error.h"
#include "femto/host.h"
#include "femto/properties.h"
#include "femto/warp.h"

namespace {

using femto::Bsdf;
using femto::BsdfSample;
using femto::Color;
using femto::Properties;
using femto::Vec2;
using femto::Vec3;
using namespace femto_test;

const femto::Hit kHit;

// ---------------------------------------------------------------------------------------------
// Building materials

std::shared_ptr<Bsdf> build(const Properties& props, const std::vector<Properties>& children = {}) {
    Properties p = props;
    for (size_t i = 0; i < children.size(); ++i)
        p.set_object("_arg_" + std::to_string(i), make_bsdf(children[i]));
    return make_bsdf(p);
}

Properties diffuse_props(Color r) {
    Properties p("diffuse", {});
    p.set_color("reflectance", r);
    return p;
}

Properties rough_props(const std::string& dist, double au, double av, bool visible,
                       const std::string& material) {
    Properties p("roughconductor", {});
    p.set_string("distribution", dist);
    if (au == av) {
        p.set_float("alpha", au);
    } else {
        p.set_float("alpha_u", au);
        p.set_float("alpha_v", av);
    }
    p.set_bool("sample_visible", visible);
    p.set_string("material", material);
    return p;
}

Properties plastic_props(Color d, Color s, const std::string& int_ior, bool nonlinear) {
    Properties p("plastic", {});
    p.set_color("diffuse_reflectance", d);
    p.set_color("specular_reflectance", s);
    p.set_string("int_ior", int_ior);
    p.set_bool("nonlinear", nonlinear);
    return p;
}

Properties roughplastic_props(const std::string& dist, double alpha, bool visible, Color d, Color s,
                              bool nonlinear, const std::string& int_ior = "polypropylene") {
    Properties p("roughplastic", {});
    p.set_string("distribution", dist);
    p.set_float("alpha", alpha);
    p.set_bool("sample_visible", visible);
    p.set_color("diffuse_reflectance", d);
    p.set_color("specular_reflectance", s);
    p.set_bool("nonlinear", nonlinear);
    p.set_string("int_ior", int_ior);
    return p;
}

/// A `mask` of opacity `alpha` over `nested`.
std::shared_ptr<Bsdf> mask_over(double alpha, const std::shared_ptr<Bsdf>& nested) {
    Properties p("mask", {});
    p.set_float("opacity", alpha);
    p.set_object("_arg_0", nested);
    return make_bsdf(p);
}

Properties dielectric_props(double int_ior, double ext_ior) {
    Properties p("dielectric", {});
    p.set_float("int_ior", int_ior);
    p.set_float("ext_ior", ext_ior);
    return p;
}

struct Material {
    std::string name;
    std::function<std::shared_ptr<Bsdf>()> make;
    bool two_sided = false;  ///< scatters from both sides (else zero when wi.z <= 0)
};

// gtest prints a parameter into the ctest name: print the case name (not the struct's bytes).
void PrintTo(const Material& m, std::ostream* os) { *os << m.name; }

/// Materials with a non-delta component.
std::vector<Material> smooth_materials() {
    std::vector<Material> m;
    m.push_back({"diffuse", [] { return build(diffuse_props(Color(0.2f, 0.5f, 0.9f))); }});
    for (const char* dist : {"beckmann", "ggx"})
        for (bool visible : {true, false}) {
            const std::string suffix = std::string(dist) + (visible ? "_visible" : "_full");
            m.push_back({"rough_" + suffix + "_a0p1",
                         [=] { return build(rough_props(dist, 0.1, 0.1, visible, "Cu")); }});
            m.push_back({"rough_" + suffix + "_a0p6",
                         [=] { return build(rough_props(dist, 0.6, 0.6, visible, "Au")); }});
            m.push_back({"rough_" + suffix + "_aniso",
                         [=] { return build(rough_props(dist, 0.1, 0.45, visible, "Al")); }});
        }
    m.push_back({"plastic", [] {
                     return build(plastic_props(Color(0.2f, 0.5f, 0.8f), Color(1.f),
                                                "polypropylene", false));
                 }});
    m.push_back({"plastic_nonlinear_diamond", [] {
                     return build(
                         plastic_props(Color(0.9f, 0.6f, 0.3f), Color(0.7f), "diamond", true));
                 }});
    for (const char* dist : {"beckmann", "ggx"}) {
        const std::string prefix = std::string("roughplastic_") + dist;
        m.push_back({prefix + "_visible_a0p1", [=] {
                         return build(roughplastic_props(dist, 0.1, true, Color(0.2f, 0.5f, 0.8f),
                                                         Color(1.f), false));
                     }});
        m.push_back({prefix + "_full_a0p4_nonlinear", [=] {
                         return build(roughplastic_props(dist, 0.4, false, Color(0.9f, 0.6f, 0.3f),
                                                         Color(0.7f), true, "diamond"));
                     }});
    }
    m.push_back({"twosided_diffuse",
                 [] { return build(Properties("twosided", {}), {diffuse_props(Color(0.6f))}); },
                 true});
    m.push_back({"twosided_diffuse_ggx",
                 [] {
                     return build(
                         Properties("twosided", {}),
                         {diffuse_props(Color(0.6f)), rough_props("ggx", 0.3, 0.3, true, "none")});
                 },
                 true});
    // mask: its pass-through is a delta lobe from both sides, so only two-sided materials
    // inside (a one-sided one would still "scatter" from below, straight through).
    m.push_back({"mask_twosided_diffuse",
                 [] {
                     return mask_over(0.6, build(Properties("twosided", {}),
                                                 {diffuse_props(Color(0.2f, 0.5f, 0.9f))}));
                 },
                 true});
    m.push_back({"mask_twosided_ggx",
                 [] {
                     return mask_over(0.7, build(Properties("twosided", {}),
                                                 {rough_props("ggx", 0.3, 0.3, true, "Cu")}));
                 },
                 true});
    return m;
}

Vec3 random_direction(femto::Pcg32& rng) {
    const float a = rng.next_float();
    return femto::warp::square_to_uniform_sphere({a, rng.next_float()});
}

double rel_diff(double a, double b) {
    const double m = std::max(std::abs(a), std::abs(b));
    return m > 0 ? std::abs(a - b) / m : 0.0;
}

// ---------------------------------------------------------------------------------------------
// sample() agrees with eval() and pdf(); reciprocity; one-sidedness

class BsdfConsistency : public ::testing::TestWithParam<Material> {};

// sample() computes its weight and pdf from the sampled microfacet normal m, eval()/pdf()
// from the half vector h = normalize(wi + wo) of the float wo = 2 (wi.m) m - wi. That sum
// cancels when wi.m is small, so h carries a relative error ~ (float epsilon) / (wi.h); over
// 1e6 samples per material the observed |rel. error| * (wi.h) stayed below 2e-5. Allowed:
// 1e-4 + 1e-4 / (wi.h) (5x that bound; 3e-4 for a typical wi.h = 0.5, still far below any
// modelling error). Diffuse lobes have no half vector (wi.h = 1 is used).
TEST_P(BsdfConsistency, SampleAgreesWithEvalAndPdf) {
    const std::shared_ptr<Bsdf> bsdf = GetParam().make();
    ASSERT_TRUE(bsdf);
    femto::Pcg32 rng(seed_from_name(GetParam().name), 7);
    double max_pdf_err = 0, max_weight_err = 0;  // in units of the allowed error
    int checked = 0;
    for (int i = 0; i < 100000; ++i) {
        const Vec3 wi = random_direction(rng);
        const float u_lobe = rng.next_float();
        const Vec2 u(rng.next_float(), rng.next_float());
        const BsdfSample s = bsdf->sample(kHit, wi, u_lobe, u);
        if (!s.valid()) continue;
        ASSERT_TRUE(s.weight.is_finite() && std::isfinite(s.pdf)) << "wi.z = " << wi.z;
        ASSERT_NEAR(length(s.wo), 1.0, 1e-5);
        if (!GetParam().two_sided) {
            ASSERT_GT(wi.z, 0.f) << "a one-sided material sampled from below";
        }
        if (s.sampled_lobe & femto::kBsdfDelta) continue;
        ASSERT_TRUE(s.sampled_lobe & bsdf->flags());
        const float pdf = bsdf->pdf(kHit, wi, s.wo);
        const Color f = bsdf->eval(kHit, wi, s.wo);
        ASSERT_GT(pdf, 0.f) << "pdf() is zero where sample() went";
        const double wi_h = (s.sampled_lobe & femto::kBsdfGlossyReflection)
                                ? std::abs(dot(wi, normalize(wi + s.wo)))
                                : 1.0;
        const double tol = 1e-4 + 1e-4 / std::max(wi_h, 1e-12);
        max_pdf_err = std::max(max_pdf_err, rel_diff(s.pdf, pdf) / tol);
        for (int c = 0; c < 3; ++c)
            max_weight_err = std::max(max_weight_err, rel_diff(s.weight[c], f[c] / pdf) / tol);
        ++checked;
    }
    std::printf("[consistency] %s: %d samples, max rel. error / allowed: pdf %.3f, weight %.3f\n",
                GetParam().name.c_str(), checked, max_pdf_err, max_weight_err);
    EXPECT_GT(checked, 25000);
    EXPECT_LE(max_pdf_err, 1.0);
    EXPECT_LE(max_weight_err, 1.0);
}

TEST_P(BsdfConsistency, Reciprocity) {
    const std::shared_ptr<Bsdf> bsdf = GetParam().make();
    femto::Pcg32 rng(seed_from_name(GetParam().name), 8);
    double max_err = 0;
    int nonzero = 0;
    for (int i = 0; i < 20000; ++i) {
        Vec3 wi = random_direction(rng), wo = random_direction(rng);
        // Reflection: both on one side (the front for one-sided materials).
        wi.z = std::abs(wi.z);
        wo.z = std::abs(wo.z);
        if (GetParam().two_sided && (i % 2)) {
            wi.z = -wi.z;
            wo.z = -wo.z;
        }
        if (std::abs(wi.z) < 1e-3f || std::abs(wo.z) < 1e-3f) continue;
        const Color a = bsdf->eval(kHit, wi, wo) / std::abs(wo.z);
        const Color b = bsdf->eval(kHit, wo, wi) / std::abs(wi.z);
        for (int c = 0; c < 3; ++c) max_err = std::max(max_err, rel_diff(a[c], b[c]));
        nonzero += a.max_component() > 0;
    }
    std::printf("[reciprocity] %s: max rel. difference %.2e over %d non-zero pairs\n",
                GetParam().name.c_str(), max_err, nonzero);
    EXPECT_GT(nonzero, 1000);
    EXPECT_LE(max_err, 1e-4);  // the same formula with swapped arguments: rounding only
}

TEST_P(BsdfConsistency, OneSidedWhereMitsubaIs) {
    const std::shared_ptr<Bsdf> bsdf = GetParam().make();
    femto::Pcg32 rng(seed_from_name(GetParam().name), 9);
    for (int i = 0; i < 2000; ++i) {
        Vec3 wi = random_direction(rng), wo = random_direction(rng);
        if (GetParam().two_sided) {
            // Transmission through a reflective two-sided material is zero.
            wi.z = std::abs(wi.z);
            wo.z = -std::abs(wo.z);
            EXPECT_TRUE(bsdf->eval(kHit, wi, wo).is_black());
            EXPECT_TRUE(bsdf->eval(kHit, wo, wi).is_black());
            EXPECT_EQ(bsdf->pdf(kHit, wi, wo), 0.f);
            continue;
        }
        wi.z = -std::abs(wi.z);  // from below: nothing
        EXPECT_TRUE(bsdf->eval(kHit, wi, wo).is_black());
        EXPECT_EQ(bsdf->pdf(kHit, wi, wo), 0.f);
        EXPECT_FALSE(bsdf->sample(kHit, wi, rng.next_float(), {0.3f, 0.6f}).valid());
        wi.z = -wi.z;  // from above toward below: nothing
        wo.z = -std::abs(wo.z);
        EXPECT_TRUE(bsdf->eval(kHit, wi, wo).is_black());
        EXPECT_EQ(bsdf->pdf(kHit, wi, wo), 0.f);
    }
}

INSTANTIATE_TEST_SUITE_P(Bsdf, BsdfConsistency, ::testing::ValuesIn(smooth_materials()),
                         [](const ::testing::TestParamInfo<Material>& info) {
                             return info.param.name;
                         });

// ---------------------------------------------------------------------------------------------
// White furnace: the mean sample weight is the directional albedo

struct Estimate {
    double mean[3] = {0, 0, 0};
    double se[3] = {0, 0, 0};  ///< standard error of the mean
};

Estimate albedo(const Bsdf& bsdf, const Vec3& wi, int n, uint64_t seed) {
    femto::Pcg32 rng(seed, 3);
    double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
    for (int i = 0; i < n; ++i) {
        const float u_lobe = rng.next_float();
        const Vec2 u(rng.next_float(), rng.next_float());
        const BsdfSample s = bsdf.sample(kHit, wi, u_lobe, u);
        if (!s.valid()) continue;  // contributes zero
        for (int c = 0; c < 3; ++c) {
            sum[c] += s.weight[c];
            sum2[c] += double(s.weight[c]) * s.weight[c];
        }
    }
    Estimate e;
    for (int c = 0; c < 3; ++c) {
        e.mean[c] = sum[c] / n;
        const double var = std::max(0.0, sum2[c] / n - e.mean[c] * e.mean[c]);
        e.se[c] = std::sqrt(var / (n - 1));
    }
    return e;
}

struct FurnaceCase {
    std::string name;
    std::function<std::shared_ptr<Bsdf>()> make;
    bool conserving;                 ///< expected albedo exactly 1 (else only <= 1)
    std::vector<double> thetas_deg;  ///< incident polar angles (> 90 = from below)
};

void PrintTo(const FurnaceCase& c, std::ostream* os) { *os << c.name; }

std::vector<FurnaceCase> furnace_cases() {
    const std::vector<double> front = {0, 30, 60, 85, 89};
    std::vector<FurnaceCase> c;
    c.push_back({"diffuse", [] { return build(diffuse_props(Color(1.f))); }, true, front});
    c.push_back({"conductor_none", [] { return build(Properties("conductor", {})); }, true, front});
    c.push_back({"dielectric",
                 [] { return build(dielectric_props(1.5, 1.0)); },
                 true,
                 {0, 30, 60, 85, 89, 120, 135, 150, 180}});
    c.push_back(
        {"plastic_white",
         [] { return build(plastic_props(Color(1.f), Color(1.f), "polypropylene", false)); }, true,
         front});
    c.push_back({"plastic_white_nonlinear_diamond",
                 [] { return build(plastic_props(Color(1.f), Color(1.f), "diamond", true)); }, true,
                 front});
    c.push_back(
        {"plastic_grey",
         [] { return build(plastic_props(Color(0.5f), Color(1.f), "polypropylene", false)); },
         false, front});
    c.push_back({"thindielectric",
                 [] {
                     Properties p("thindielectric", {});
                     p.set_float("int_ior", 1.7);
                     return build(p);
                 },
                 true,
                 {0, 30, 60, 85, 89, 120, 150, 180}});
    c.push_back({"twosided_diffuse",
                 [] { return build(Properties("twosided", {}), {diffuse_props(Color(1.f))}); },
                 true,
                 {10, 60, 120, 170}});
    c.push_back({"null", [] { return build(Properties("null", {})); }, true, {0, 60, 120}});
    // A mask over a white material passes what the material does not take: all light.
    c.push_back({"mask_white_diffuse",
                 [] { return mask_over(0.4, build(diffuse_props(Color(1.f)))); }, true, front});
    c.push_back({"mask_twosided_white_diffuse",
                 [] {
                     return mask_over(
                         0.8, build(Properties("twosided", {}), {diffuse_props(Color(1.f))}));
                 },
                 true,
                 {10, 60, 120, 170}});
    for (const char* dist : {"beckmann", "ggx"})
        for (bool visible : {true, false})
            for (double a : {0.05, 0.3, 1.0}) {
                char name[96];
                std::snprintf(name, sizeof name, "rough_%s_%s_alpha%g", dist,
                              visible ? "visible" : "full", a);
                std::string n(name);
                std::replace(n.begin(), n.end(), '.', 'p');
                c.push_back({n, [=] { return build(rough_props(dist, a, a, visible, "none")); },
                             false, front});
            }
    // roughplastic loses what the single-scattering microfacet model loses: at most one. With a
    // black base only the coating's specular lobe is left.
    for (const char* dist : {"beckmann", "ggx"})
        for (double a : {0.05, 0.5})
            for (float base : {1.f, 0.f}) {
                char name[96];
                std::snprintf(name, sizeof name, "roughplastic_%s_alpha%g_%s", dist, a,
                              base > 0.f ? "white" : "black_base");
                std::string n(name);
                std::replace(n.begin(), n.end(), '.', 'p');
                c.push_back({n,
                             [=] {
                                 return build(roughplastic_props(dist, a, true, Color(base),
                                                                 Color(1.f), false));
                             },
                             false, front});
            }
    c.push_back({"rough_ggx_aniso",
                 [] { return build(rough_props("ggx", 0.05, 0.8, true, "none")); }, false, front});
    return c;
}

class BsdfFurnace : public ::testing::TestWithParam<FurnaceCase> {};

TEST_P(BsdfFurnace, AlbedoAtMostOne) {
    const FurnaceCase& fc = GetParam();
    const std::shared_ptr<Bsdf> bsdf = fc.make();
    ASSERT_TRUE(bsdf);
    const int n = 200000;
    for (double theta : fc.thetas_deg) {
        const Estimate e = albedo(*bsdf, direction_deg(theta, 0.4), n,
                                  seed_from_name(fc.name) + static_cast<uint64_t>(theta));
        std::printf("[furnace] %s at %g deg: albedo %.6f +- %.6f\n", fc.name.c_str(), theta,
                    e.mean[0], e.se[0]);
        for (int c = 0; c < 3; ++c) {
            EXPECT_LE(e.mean[c], 1.0 + 3.0 * e.se[c] + 1e-6) << fc.name << " at " << theta;
            if (fc.conserving) {
                EXPECT_NEAR(e.mean[c], 1.0, 4.0 * e.se[c] + 1e-6) << fc.name << " at " << theta;
            }
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Bsdf, BsdfFurnace, ::testing::ValuesIn(furnace_cases()),
                         [](const ::testing::TestParamInfo<FurnaceCase>& info) {
                             return info.param.name;
                         });

// ---------------------------------------------------------------------------------------------
// The mean sample weight equals the integral of eval() (plus the delta lobes' reflectance):
// sampling covers the whole lobe and weights are unbiased, for both microfacet samplers.

/// Integral of eval() over the sphere, per channel: adaptive Simpson over 32 x 64 bins in
/// (cos theta, phi), each to max(1e-9, 1e-6 |I_bin|): total error < 2048e-9 + 1e-6 = 3e-6.
Color integrate_eval(const Bsdf& bsdf, const Vec3& wi) {
    Color total(0.f);
    const int nx = 32, ny = 64;
    for (int c = 0; c < 3; ++c) {
        double sum = 0;
        for (int ix = 0; ix < nx; ++ix)
            for (int iy = 0; iy < ny; ++iy) {
                const double x0 = -1.0 + 2.0 * ix / nx, y0 = 2 * kPi * iy / ny;
                sum += integrate_2d(
                    [&](double z, double phi) {
                        return double(bsdf.eval(kHit, wi, sphere_direction(z, phi))[c]);
                    },
                    x0, x0 + 2.0 / nx, y0, y0 + 2 * kPi / ny, 1e-9, 1e-6);
            }
        total[c] = static_cast<float>(sum);
    }
    return total;
}

/// Dielectric Fresnel reflectance in Fresnel's own form (the angles, not the cosines):
/// R_s = sin^2(ti - tt) / sin^2(ti + tt), R_p = tan^2(ti - tt) / tan^2(ti + tt), for light in a
/// medium of index n1 meeting one of index n2; 1 beyond the critical angle.
double fresnel_reference(double cos_i, double n1, double n2) {
    const double ti = std::acos(std::clamp(cos_i, -1.0, 1.0));
    const double st = n1 / n2 * std::sin(ti);
    if (st >= 1.0) return 1.0;
    const double tt = std::asin(st);
    if (ti == 0.0) return std::pow((n1 - n2) / (n1 + n2), 2);
    const double rs = std::pow(std::sin(ti - tt) / std::sin(ti + tt), 2);
    const double rp = std::pow(std::tan(ti - tt) / std::tan(ti + tt), 2);
    return 0.5 * (rs + rp);
}

TEST(BsdfAlbedo, RoughConductorSamplersAgreeWithQuadrature) {
    for (const char* dist : {"beckmann", "ggx"})
        for (double alpha : {0.1, 0.5})
            for (double theta : {30.0, 75.0}) {
                const Vec3 wi = direction_deg(theta, 0.3);
                const std::shared_ptr<Bsdf> vis =
                    build(rough_props(dist, alpha, alpha, true, "Cu"));
                const std::shared_ptr<Bsdf> full =
                    build(rough_props(dist, alpha, alpha, false, "Cu"));
                const Color ref = integrate_eval(*vis, wi);
                const Color ref_full = integrate_eval(*full, wi);
                const uint64_t seed =
                    seed_from_name(dist) + static_cast<uint64_t>(theta * 100 + alpha * 10);
                const Estimate ev = albedo(*vis, wi, 200000, seed);
                const Estimate ef = albedo(*full, wi, 200000, seed + 1);
                std::printf(
                    "[albedo] %s alpha %g at %g deg: quadrature %.5f, visible %.5f +- %.5f, "
                    "full %.5f +- %.5f (red)\n",
                    dist, alpha, theta, ref[0], ev.mean[0], ev.se[0], ef.mean[0], ef.se[0]);
                for (int c = 0; c < 3; ++c) {
                    EXPECT_NEAR(ref[c], ref_full[c],
                                1e-5);  // the same eval(): quadrature error only
                    // 4 standard errors plus the quadrature error bound (3e-6, rounded up).
                    EXPECT_NEAR(ev.mean[c], ref[c], 4 * ev.se[c] + 1e-5) << dist << alpha << theta;
                    EXPECT_NEAR(ef.mean[c], ref[c], 4 * ef.se[c] + 1e-5) << dist << alpha << theta;
                }
            }
}

// An analytic albedo: a GGX mirror (F = 1) with alpha = 1 seen at normal incidence. With
// u uniform, tan^2(theta_m) = u / (1 - u) samples D(m) cos(theta_m) (= the visible normals,
// as G1(wi) = 1), theta_o = 2 theta_m stays above the horizon for u < 1/2, and
// G1(wo) = 2 cos(theta_o) / (1 + cos(theta_o)) = (1 - 2u) / (1 - u), so
// E = integral_0^1/2 (1 - 2u) / (1 - u) du = 1 - ln 2.
TEST(BsdfAlbedo, GgxAlphaOneNormalIncidenceIsOneMinusLnTwo) {
    for (bool visible : {true, false}) {
        const std::shared_ptr<Bsdf> bsdf = build(rough_props("ggx", 1.0, 1.0, visible, "none"));
        const Estimate e = albedo(*bsdf, Vec3(0, 0, 1), 400000, visible ? 5 : 6);
        std::printf("[albedo] ggx alpha 1, normal incidence (%s): %.5f +- %.5f, 1 - ln 2 = %.5f\n",
                    visible ? "visible" : "full", e.mean[0], e.se[0], 1.0 - std::log(2.0));
        EXPECT_NEAR(e.mean[0], 1.0 - std::log(2.0), 4 * e.se[0]);
        const Color q = integrate_eval(*bsdf, Vec3(0, 0, 1));
        EXPECT_NEAR(q[0], 1.0 - std::log(2.0), 1e-5);  // quadrature error bound 3e-6
    }
}

TEST(BsdfAlbedo, PlasticEqualsSpecularFresnelPlusDiffuseIntegral) {
    const double n_int = 1.49, n_ext = 1.000277;  // polypropylene in air (the defaults)
    const Color d(0.2f, 0.5f, 0.8f), s(0.9f, 0.7f, 0.5f);
    const std::shared_ptr<Bsdf> plastic = build(plastic_props(d, s, "polypropylene", false));
    for (double theta : {0.0, 40.0, 70.0, 85.0}) {
        const Vec3 wi = direction_deg(theta, 1.1);
        const double f = fresnel_reference(wi.z, n_ext, n_int);
        const Color diffuse = integrate_eval(*plastic, wi);
        const Estimate e = albedo(*plastic, wi, 200000, 77 + static_cast<uint64_t>(theta));
        for (int c = 0; c < 3; ++c) {
            const double expected = s[c] * f + diffuse[c];
            EXPECT_NEAR(e.mean[c], expected, 4 * e.se[c] + 1e-5) << "theta " << theta << " c " << c;
        }
        std::printf("[albedo] plastic at %g deg: F = %.5f, diffuse (red) %.5f, mean %.5f +- %.5f\n",
                    theta, f, diffuse[0], e.mean[0], e.se[0]);
    }
}

// As alpha -> 0 roughplastic's rough coating becomes plastic's smooth one: T -> 1 - F,
// R_int -> Fdr_int and the specular lobe's albedo -> F. At alpha = 1e-3 what remains differs by
// O(alpha^2) ~ 1e-6 plus the linear interpolation of T between 64 cosines (< 1e-4 on the
// albedo), both far below the estimate's standard error (~1e-3), so the mean sample weight of
// roughplastic must equal plastic's exact albedo (F s plus the quadrature of its diffuse lobe)
// within 4 standard errors. With a black base the albedo is the Fresnel reflectance alone.
TEST(BsdfAlbedo, RoughPlasticTendsToPlasticAtSmallAlpha) {
    const double n_int = 1.49, n_ext = 1.000277;  // polypropylene in air (the defaults)
    const Color s(1.f);
    for (const Color& d : {Color(0.2f, 0.5f, 0.8f), Color(0.f)})
        for (bool nonlinear : {false, true}) {
            if (d.is_black() && nonlinear) continue;  // the same material
            const std::shared_ptr<Bsdf> plastic =
                build(plastic_props(d, s, "polypropylene", nonlinear));
            for (double theta : {0.0, 60.0}) {
                const Vec3 wi = direction_deg(theta, 0.9);
                const double f = fresnel_reference(wi.z, n_ext, n_int);
                const Color diffuse = integrate_eval(*plastic, wi);
                for (const char* dist : {"beckmann", "ggx"}) {
                    const std::shared_ptr<Bsdf> rough =
                        build(roughplastic_props(dist, 1e-3, true, d, s, nonlinear));
                    const Estimate e = albedo(*rough, wi, 400000,
                                              seed_from_name(dist) + static_cast<uint64_t>(theta));
                    std::printf(
                        "[albedo] roughplastic %s alpha 1e-3 base %.1f%s at %g deg: %.5f +- "
                        "%.5f, plastic %.5f (red)\n",
                        dist, d[0], nonlinear ? " nonlinear" : "", theta, e.mean[0], e.se[0],
                        s[0] * f + diffuse[0]);
                    for (int c = 0; c < 3; ++c)
                        EXPECT_NEAR(e.mean[c], s[c] * f + diffuse[c], 4 * e.se[c] + 1e-5)
                            << dist << " theta " << theta << " channel " << c;
                }
            }
        }
}

// With a black base roughplastic is its coating's specular lobe alone: the mean sample weight
// equals the integral of eval() (the samplers cover the lobe and weigh it without bias), and
// the coating reflects less than all light.
TEST(BsdfAlbedo, RoughPlasticSpecularLobeAgreesWithQuadrature) {
    for (const char* dist : {"beckmann", "ggx"})
        for (double alpha : {0.1, 0.5})
            for (bool visible : {true, false})
                for (double theta : {30.0, 75.0}) {
                    const Vec3 wi = direction_deg(theta, 0.3);
                    const std::shared_ptr<Bsdf> bsdf = build(
                        roughplastic_props(dist, alpha, visible, Color(0.f), Color(1.f), false));
                    const Color ref = integrate_eval(*bsdf, wi);
                    const Estimate e = albedo(*bsdf, wi, 200000,
                                              seed_from_name(dist) +
                                                  static_cast<uint64_t>(theta * 100 + alpha * 10) +
                                                  (visible ? 0 : 7));
                    std::printf(
                        "[albedo] roughplastic %s alpha %g %s, black base, at %g deg: quadrature "
                        "%.5f, samples %.5f +- %.5f\n",
                        dist, alpha, visible ? "visible" : "full", theta, ref[0], e.mean[0],
                        e.se[0]);
                    EXPECT_LT(ref[0], 1.0);
                    // 4 standard errors plus the quadrature error bound (3e-6, rounded up).
                    EXPECT_NEAR(e.mean[0], ref[0], 4 * e.se[0] + 1e-5) << dist << alpha << theta;
                }
}

// ---------------------------------------------------------------------------------------------
// dielectric

/// Fraction of reflection samples and the properties of every sample at one incidence.
struct DielectricStats {
    double reflected_fraction = 0;
    float reflect_pdf = -1;
    int n = 0;
};

DielectricStats dielectric_stats(const Bsdf& bsdf, const Vec3& wi, double n_i, double n_t, int n,
                                 uint64_t seed) {
    DielectricStats st;
    femto::Pcg32 rng(seed, 5);
    int reflected = 0;
    for (int i = 0; i < n; ++i) {
        const BsdfSample s = bsdf.sample(kHit, wi, rng.next_float(), {0.5f, 0.5f});
        EXPECT_TRUE(s.valid());
        EXPECT_EQ(s.weight, Color(1.f));
        EXPECT_NEAR(length(s.wo), 1.0, 1e-5);
        if (s.sampled_lobe == femto::kBsdfDeltaReflection) {
            ++reflected;
            st.reflect_pdf = s.pdf;
            EXPECT_EQ(s.eta, 1.f);
            EXPECT_NEAR(s.wo.x, -wi.x, 1e-7);
            EXPECT_NEAR(s.wo.y, -wi.y, 1e-7);
            EXPECT_EQ(s.wo.z, wi.z);
        } else {
            EXPECT_EQ(s.sampled_lobe, femto::kBsdfDeltaTransmission);
            // Snell's law, the other side, the opposite azimuth, eta = n_t / n_i.
            const double sin_i = std::sqrt(std::max(0.0, 1.0 - double(wi.z) * wi.z));
            const double sin_t = std::sqrt(std::max(0.0, 1.0 - double(s.wo.z) * s.wo.z));
            EXPECT_NEAR(n_i * sin_i, n_t * sin_t, 1e-5);
            EXPECT_LT(s.wo.z * wi.z, 0.f);
            EXPECT_LE(s.wo.x * wi.x + s.wo.y * wi.y, 1e-7f);
            EXPECT_NEAR(s.wo.x * wi.y - s.wo.y * wi.x, 0.0, 1e-6);
            EXPECT_NEAR(s.eta, n_t / n_i, 1e-6 * n_t / n_i);
            EXPECT_NEAR(s.pdf, 1.0 - fresnel_reference(std::abs(wi.z), n_i, n_t), 1e-5);
        }
        EXPECT_EQ(bsdf.eval(kHit, wi, s.wo), Color(0.f));
        EXPECT_EQ(bsdf.pdf(kHit, wi, s.wo), 0.f);
    }
    st.reflected_fraction = double(reflected) / n;
    st.n = n;
    return st;
}

TEST(BsdfDielectric, NormalIncidenceReflectance) {
    struct Case {
        const char* int_name;
        const char* ext_name;
        double n2, n1;
    };
    const Case cases[] = {{nullptr, nullptr, 1.5, 1.0},
                          {"water", "vacuum", 1.3330, 1.0},
                          {"diamond", "air", 2.419, 1.000277},
                          {"BK7", "water", 1.5046, 1.3330}};
    for (const Case& c : cases) {
        Properties p("dielectric", {});
        if (c.int_name) {
            p.set_string("int_ior", c.int_name);
            p.set_string("ext_ior", c.ext_name);
        } else {
            p.set_float("int_ior", c.n2);
            p.set_float("ext_ior", c.n1);
        }
        const std::shared_ptr<Bsdf> bsdf = build(p);
        const double r0 = std::pow((c.n1 - c.n2) / (c.n1 + c.n2), 2);
        const int n = 400000;
        const DielectricStats st = dielectric_stats(*bsdf, Vec3(0, 0, 1), c.n1, c.n2, n, 21);
        // The reflection probability reported by sample() is R itself (float evaluation).
        EXPECT_NEAR(st.reflect_pdf, r0, 1e-6) << (c.int_name ? c.int_name : "1.5");
        // The fraction of reflections is binomial(n, R0): 4 standard errors.
        EXPECT_NEAR(st.reflected_fraction, r0, 4 * std::sqrt(r0 * (1 - r0) / n));
        // From inside, at normal incidence, the same R0.
        const DielectricStats in = dielectric_stats(*bsdf, Vec3(0, 0, -1), c.n2, c.n1, n, 22);
        EXPECT_NEAR(in.reflect_pdf, r0, 1e-6);
        EXPECT_NEAR(in.reflected_fraction, r0, 4 * std::sqrt(r0 * (1 - r0) / n));
    }
}

TEST(BsdfDielectric, ObliqueFresnelAndSnell) {
    const double n_ext = 1.0, n_int = 1.5;
    const std::shared_ptr<Bsdf> bsdf = build(dielectric_props(n_int, n_ext));
    const int n = 100000;
    for (double theta : {10.0, 35.0, 56.3, 70.0, 85.0, 89.5}) {  // 56.3 ~ Brewster's angle
        const Vec3 wi = direction_deg(theta, 0.9);
        const double r = fresnel_reference(wi.z, n_ext, n_int);
        const DielectricStats st = dielectric_stats(*bsdf, wi, n_ext, n_int, n, 31);
        if (st.reflect_pdf >= 0) {
            EXPECT_NEAR(st.reflect_pdf, r, 1e-5) << theta;
        }
        EXPECT_NEAR(st.reflected_fraction, r, 4 * std::sqrt(r * (1 - r) / n) + 1e-6) << theta;
    }
    // From inside, below the critical angle asin(1 / 1.5) = 41.81 deg.
    for (double theta : {10.0, 30.0, 41.0}) {
        const Vec3 wi = direction_deg(180.0 - theta, 0.2);
        const double r = fresnel_reference(-wi.z, n_int, n_ext);
        const DielectricStats st = dielectric_stats(*bsdf, wi, n_int, n_ext, n, 32);
        EXPECT_LT(r, 1.0);
        EXPECT_NEAR(st.reflected_fraction, r, 4 * std::sqrt(r * (1 - r) / n) + 1e-6) << theta;
    }
}

TEST(BsdfDielectric, TotalInternalReflection) {
    const std::shared_ptr<Bsdf> bsdf = build(dielectric_props(1.5, 1.0));
    for (double theta : {42.0, 50.0, 70.0, 89.0}) {  // beyond the critical angle 41.81 deg
        const Vec3 wi = direction_deg(180.0 - theta, 2.0);
        for (float u : {0.f, 0.25f, 0.5f, 0.999f, 0x1.fffffep-1f}) {
            const BsdfSample s = bsdf->sample(kHit, wi, u, {0.5f, 0.5f});
            ASSERT_TRUE(s.valid());
            EXPECT_EQ(s.sampled_lobe, femto::kBsdfDeltaReflection) << theta;
            EXPECT_EQ(s.pdf, 1.f);
            EXPECT_EQ(s.weight, Color(1.f));
            EXPECT_EQ(s.wo, Vec3(-wi.x, -wi.y, wi.z));
        }
    }
}

TEST(BsdfDielectric, SpecularFactorsScaleTheWeights) {
    Properties p = dielectric_props(1.33, 1.0);
    p.set_color("specular_reflectance", Color(0.5f, 0.6f, 0.7f));
    p.set_color("specular_transmittance", Color(0.1f, 0.2f, 0.3f));
    const std::shared_ptr<Bsdf> bsdf = build(p);
    const Vec3 wi = direction_deg(50.0);
    const BsdfSample r = bsdf->sample(kHit, wi, 0.f, {0, 0});
    const BsdfSample t = bsdf->sample(kHit, wi, 0.9999f, {0, 0});
    EXPECT_EQ(r.sampled_lobe, femto::kBsdfDeltaReflection);
    EXPECT_EQ(r.weight, Color(0.5f, 0.6f, 0.7f));
    EXPECT_EQ(t.sampled_lobe, femto::kBsdfDeltaTransmission);
    EXPECT_EQ(t.weight, Color(0.1f, 0.2f, 0.3f));
    EXPECT_EQ(bsdf->flags(), femto::kBsdfDeltaReflection | femto::kBsdfDeltaTransmission);
    EXPECT_TRUE(bsdf->has_delta_only());
}

// ---------------------------------------------------------------------------------------------
// thindielectric

// A slab reflects R' = R + T^2 R / (1 - R^2) = 2R / (1 + R) of the light (R and T = 1 - R for one
// face), summed over its internal bounces, and lets T' = 1 - R' through undeviated: the
// fraction of reflection samples is R' within 4 binomial standard errors, every sample has weight
// one (so R' + T' = 1: the furnace case above), a transmission leaves along -wi with eta = 1 (the
// path's index is unchanged) and a reflection along the mirror direction, from either side.
TEST(BsdfThinDielectric, SlabReflectanceAndStraightTransmission) {
    const double n_int = 1.5046, n_ext = 1.000277;  // the defaults: bk7 in air
    const std::shared_ptr<Bsdf> bsdf = build(Properties("thindielectric", {}));
    EXPECT_EQ(bsdf->flags(), femto::kBsdfDeltaReflection | femto::kBsdfDeltaTransmission);
    const int n = 200000;
    for (double theta : {0.0, 30.0, 60.0, 80.0, 89.0, 120.0, 170.0}) {
        const Vec3 wi = direction_deg(theta, 0.8);
        const double r = fresnel_reference(std::abs(wi.z), n_ext, n_int);
        const double r_slab = r + (1 - r) * (1 - r) * r / (1 - r * r);
        femto::Pcg32 rng(seed_from_name("thindielectric") + static_cast<uint64_t>(theta), 5);
        int reflected = 0;
        for (int i = 0; i < n; ++i) {
            const BsdfSample s = bsdf->sample(kHit, wi, rng.next_float(), {0.5f, 0.5f});
            ASSERT_TRUE(s.valid());
            ASSERT_EQ(s.weight, Color(1.f));
            ASSERT_EQ(s.eta, 1.f);
            if (s.sampled_lobe == femto::kBsdfDeltaReflection) {
                ++reflected;
                ASSERT_EQ(s.wo, Vec3(-wi.x, -wi.y, wi.z));
                ASSERT_NEAR(s.pdf, r_slab, 1e-5);
            } else {
                ASSERT_EQ(s.sampled_lobe, femto::kBsdfDeltaTransmission);
                ASSERT_EQ(s.wo, -wi);
                ASSERT_NEAR(s.pdf, 1 - r_slab, 1e-5);
            }
        }
        const double fraction = double(reflected) / n;
        std::printf("[thindielectric] %g deg: R = %.5f, R' = %.5f, reflected fraction %.5f\n",
                    theta, r, r_slab, fraction);
        EXPECT_NEAR(fraction, r_slab, 4 * std::sqrt(r_slab * (1 - r_slab) / n) + 1e-6) << theta;
    }
    EXPECT_EQ(bsdf->eval(kHit, direction_deg(30.0), -direction_deg(30.0)), Color(0.f));
    EXPECT_EQ(bsdf->pdf(kHit, direction_deg(30.0), -direction_deg(30.0)), 0.f);
}

TEST(BsdfThinDielectric, SpecularFactorsScaleTheWeights) {
    Properties p("thindielectric", {});
    p.set_color("specular_reflectance", Color(0.5f, 0.6f, 0.7f));
    p.set_color("specular_transmittance", Color(0.1f, 0.2f, 0.3f));
    const std::shared_ptr<Bsdf> bsdf = build(p);
    const BsdfSample r = bsdf->sample(kHit, direction_deg(50.0), 0.f, {0, 0});
    const BsdfSample t = bsdf->sample(kHit, direction_deg(50.0), 0.9999f, {0, 0});
    EXPECT_EQ(r.sampled_lobe, femto::kBsdfDeltaReflection);
    EXPECT_EQ(r.weight, Color(0.5f, 0.6f, 0.7f));
    EXPECT_EQ(t.sampled_lobe, femto::kBsdfDeltaTransmission);
    EXPECT_EQ(t.weight, Color(0.1f, 0.2f, 0.3f));
}

// ---------------------------------------------------------------------------------------------
// conductor

/// Conductor reflectance from the complex Fresnel amplitudes (relative IOR eta + i k):
/// cos_t = sqrt(1 - sin_i^2 / eta^2), r_s = (cos_i - eta cos_t) / (cos_i + eta cos_t),
/// r_p = (eta cos_i - cos_t) / (eta cos_i + cos_t), R = (|r_s|^2 + |r_p|^2) / 2.
double conductor_reference(double cos_i, double eta, double k) {
    using C = std::complex<double>;
    const C n(eta, k);
    const double sin2 = 1.0 - cos_i * cos_i;
    const C cos_t = std::sqrt(C(1.0) - sin2 / (n * n));
    const C rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
    const C rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
    return 0.5 * (std::norm(rs) + std::norm(rp));
}

TEST(BsdfConductor, FresnelMatchesComplexAmplitudes) {
    struct Case {
        Color eta, k;
        double ext;
    };
    const Case cases[] = {
        {Color(0.2004376970f, 0.9240334304f, 1.1022119527f),
         Color(3.9129485033f, 2.4528477015f, 2.1421879552f), 1.0},  // Cu
        {Color(0.1431189557f, 0.3749570432f, 1.4424785571f),
         Color(3.9831604247f, 2.3857207478f, 1.6032152899f), 1.0},  // Au
        {Color(1.5f, 2.5f, 0.8f), Color(0.0f, 0.5f, 7.0f), 1.33},   // incl. k = 0 (dielectric)
    };
    for (const Case& c : cases)
        for (bool rough : {false, true}) {
            Properties p(rough ? "roughconductor" : "conductor", {});
            p.set_color("eta", c.eta);
            p.set_color("k", c.k);
            p.set_float("ext_eta", c.ext);
            if (rough) p.set_float("alpha", 1e-4);  // clamped minimum: a near-mirror
            const std::shared_ptr<Bsdf> bsdf = build(p);
            if (rough) continue;  // (the rough variant is only built, to check the parameters)
            for (double theta : {0.0, 20.0, 45.0, 70.0, 85.0, 89.0}) {
                const Vec3 wi = direction_deg(theta, 0.5);
                const BsdfSample s = bsdf->sample(kHit, wi, 0.5f, {0.5f, 0.5f});
                ASSERT_TRUE(s.valid());
                EXPECT_EQ(s.sampled_lobe, femto::kBsdfDeltaReflection);
                EXPECT_EQ(s.pdf, 1.f);
                EXPECT_EQ(s.wo, Vec3(-wi.x, -wi.y, wi.z));
                for (int ch = 0; ch < 3; ++ch) {
                    const double ref =
                        conductor_reference(wi.z, c.eta[ch] / c.ext, c.k[ch] / c.ext);
                    EXPECT_NEAR(s.weight[ch], ref, 1e-5 * std::max(1.0, ref))
                        << "theta " << theta << " channel " << ch;
                }
            }
        }
}

TEST(BsdfConductor, PresetsAndNormalIncidence) {
    // Presets are the documented RGB triples: normal incidence R = ((n-1)^2 + k^2) / ((n+1)^2 +
    // k^2).
    struct Preset {
        const char* name;
        Color eta, k;
    };
    const Preset presets[] = {
        {"Au",
         {0.1431189557f, 0.3749570432f, 1.4424785571f},
         {3.9831604247f, 2.3857207478f, 1.6032152899f}},
        {"Ag",
         {0.1552646489f, 0.1167232965f, 0.1383806959f},
         {4.8283433224f, 3.1222459278f, 2.1469504455f}},
        {"Cu",
         {0.2004376970f, 0.9240334304f, 1.1022119527f},
         {3.9129485033f, 2.4528477015f, 2.1421879552f}},
        {"Al",
         {1.6574599595f, 0.8803689579f, 0.5212287346f},
         {9.2238691996f, 6.2695232477f, 4.8370012281f}},
    };
    for (const Preset& pr : presets) {
        Properties p("conductor", {});
        p.set_string("material", pr.name);
        const BsdfSample s = build(p)->sample(kHit, Vec3(0, 0, 1), 0.5f, {0.5f, 0.5f});
        for (int c = 0; c < 3; ++c) {
            const double n = pr.eta[c], k = pr.k[c];
            const double r0 = ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k);
            EXPECT_NEAR(s.weight[c], r0, 1e-5) << pr.name << " channel " << c;
        }
    }
    // Gold is yellow, silver and aluminium are bright and neutral-ish.
    Properties au("conductor", {});
    au.set_string("material", "Au");
    const Color gold = build(au)->sample(kHit, Vec3(0, 0, 1), 0.5f, {}).weight;
    EXPECT_GT(gold.r, gold.g);
    EXPECT_GT(gold.g, gold.b);
}

TEST(BsdfConductor, NoneIsAPerfectMirrorAndOneSided) {
    Properties p("conductor", {});
    p.set_color("specular_reflectance", Color(0.25f, 0.5f, 0.75f));
    const std::shared_ptr<Bsdf> bsdf = build(p);
    for (double theta : {0.0, 45.0, 89.9}) {
        const BsdfSample s = bsdf->sample(kHit, direction_deg(theta), 0.5f, {0.5f, 0.5f});
        EXPECT_EQ(s.weight, Color(0.25f, 0.5f, 0.75f));
    }
    EXPECT_FALSE(bsdf->sample(kHit, direction_deg(120.0), 0.5f, {0.5f, 0.5f}).valid());
    EXPECT_EQ(bsdf->eval(kHit, direction_deg(30.0), direction_deg(30.0, kPi)), Color(0.f));
    EXPECT_EQ(bsdf->pdf(kHit, direction_deg(30.0), direction_deg(30.0, kPi)), 0.f);
    EXPECT_EQ(bsdf->flags(), femto::kBsdfDeltaReflection);
}

// ---------------------------------------------------------------------------------------------
// null, twosided

TEST(BsdfNull, PassesStraightThrough) {
    const std::shared_ptr<Bsdf> bsdf = build(Properties("null", {}));
    EXPECT_EQ(bsdf->flags(), femto::kBsdfNull);
    EXPECT_TRUE(bsdf->is_null());
    for (double theta : {0.0, 60.0, 120.0, 180.0}) {
        const Vec3 wi = direction_deg(theta, 0.3);
        const BsdfSample s = bsdf->sample(kHit, wi, 0.7f, {0.1f, 0.9f});
        EXPECT_EQ(s.wo, -wi);
        EXPECT_EQ(s.weight, Color(1.f));
        EXPECT_EQ(s.pdf, 1.f);
        EXPECT_EQ(s.sampled_lobe, femto::kBsdfNull);
        EXPECT_EQ(bsdf->eval(kHit, wi, -wi), Color(0.f));
        EXPECT_EQ(bsdf->pdf(kHit, wi, -wi), 0.f);
    }
}

TEST(BsdfTwoSided, BackSideUsesSecondChildInMirroredFrame) {
    const std::shared_ptr<Bsdf> front = build(diffuse_props(Color(0.2f)));
    const std::shared_ptr<Bsdf> back = build(rough_props("ggx", 0.3, 0.3, true, "Cu"));
    Properties p("twosided", {});
    p.set_object("_arg_0", front);
    p.set_object("_arg_1", back);
    const std::shared_ptr<Bsdf> two = build(p);
    EXPECT_EQ(two->flags(), femto::kBsdfDiffuseReflection | femto::kBsdfGlossyReflection);
    femto::Pcg32 rng(99, 1);
    auto flip = [](Vec3 v) { return Vec3(v.x, v.y, -v.z); };
    for (int i = 0; i < 1000; ++i) {
        Vec3 wi = random_direction(rng), wo = random_direction(rng);
        wi.z = std::abs(wi.z);
        wo.z = std::abs(wo.z);
        EXPECT_EQ(two->eval(kHit, wi, wo), front->eval(kHit, wi, wo));
        EXPECT_EQ(two->pdf(kHit, wi, wo), front->pdf(kHit, wi, wo));
        EXPECT_EQ(two->eval(kHit, flip(wi), flip(wo)), back->eval(kHit, wi, wo));
        EXPECT_EQ(two->pdf(kHit, flip(wi), flip(wo)), back->pdf(kHit, wi, wo));
        const Vec2 u(rng.next_float(), rng.next_float());
        const BsdfSample sb = two->sample(kHit, flip(wi), 0.5f, u);
        const BsdfSample rb = back->sample(kHit, wi, 0.5f, u);
        ASSERT_EQ(sb.valid(), rb.valid());
        if (rb.valid()) {
            EXPECT_EQ(sb.wo, flip(rb.wo));
            EXPECT_EQ(sb.weight, rb.weight);
            EXPECT_EQ(sb.pdf, rb.pdf);
        }
    }
    EXPECT_FALSE(two->sample(kHit, Vec3(1, 0, 0), 0.5f, {0.5f, 0.5f}).valid());  // wi.z == 0
}

TEST(BsdfTwoSided, NeedsOneOrTwoChildren) {
    EXPECT_THROW(build(Properties("twosided", {})), femto::SceneError);
    const std::vector<Properties> three(3, diffuse_props(Color(0.5f)));
    EXPECT_THROW(build(Properties("twosided", {}), three), femto::SceneError);
}

// ---------------------------------------------------------------------------------------------
// Parameters: validation, and every schema entry is read

TEST(BsdfParams, BadValuesAreRejected) {
    auto expect_error = [](Properties p, const char* what) {
        EXPECT_THROW(build(p), femto::SceneError) << what;
    };
    {
        Properties p("roughconductor", {});
        p.set_float("alpha", 0.0);
        expect_error(p, "alpha = 0");
    }
    {
        Properties p("roughconductor", {});
        p.set_float("alpha", -0.2);
        expect_error(p, "alpha < 0");
    }
    {
        Properties p("roughconductor", {});
        p.set_float("alpha", 0.2);
        p.set_float("alpha_u", 0.2);
        expect_error(p, "alpha and alpha_u");
    }
    {
        Properties p("roughconductor", {});
        p.set_float("alpha_u", 0.2);
        expect_error(p, "alpha_u without alpha_v");
    }
    {
        Properties p("roughconductor", {});
        p.set_float("alpha_u", 0.2);
        p.set_float("alpha_v", -1);
        expect_error(p, "alpha_v < 0");
    }
    {
        Properties p("roughconductor", {});
        p.set_string("distribution", "phong");
        expect_error(p, "unknown distribution");
    }
    {
        Properties p("conductor", {});
        p.set_string("material", "Unobtainium");
        expect_error(p, "unknown preset");
    }
    {
        Properties p("conductor", {});
        p.set_string("material", "Au");
        p.set_color("eta", Color(1.f));
        expect_error(p, "preset and eta");
    }
    {
        Properties p("conductor", {});
        p.set_color("k", Color(-1.f));
        expect_error(p, "k < 0");
    }
    {
        Properties p("conductor", {});
        p.set_float("ext_eta", 0.0);
        expect_error(p, "ext_eta = 0");
    }
    {
        Properties p("dielectric", {});
        p.set_float("int_ior", -1.5);
        expect_error(p, "int_ior < 0");
    }
    {
        Properties p("dielectric", {});
        p.set_string("ext_ior", "jelly");
        expect_error(p, "unknown IOR name");
    }
    {
        Properties p("plastic", {});
        p.set_float("int_ior", 0.0);
        expect_error(p, "plastic int_ior = 0");
    }
    {
        Properties p("roughplastic", {});
        p.set_float("alpha", 0.0);
        expect_error(p, "roughplastic alpha = 0");
    }
    {
        Properties p("roughplastic", {});
        p.set_string("distribution", "phong");
        expect_error(p, "roughplastic phong (Mitsuba 0.6)");
    }
    {
        Properties p("roughplastic", {});
        p.set_float("alpha_u", 0.1);
        p.set_float("alpha_v", 0.2);
        expect_error(p, "roughplastic is isotropic");
    }
    {
        Properties p("roughplastic", {});
        p.set_float("int_ior", 1.3);
        p.set_float("ext_ior", 1.3);
        expect_error(p, "roughplastic without an index step");
    }
    {
        Properties p("thindielectric", {});
        p.set_float("int_ior", -1.5);
        expect_error(p, "thindielectric int_ior < 0");
    }
    {
        Properties p("diffuse", {});
        p.set_float("reflectence", 0.5);  // misspelt: not in the schema
        expect_error(p, "unknown parameter");
    }
}

TEST(BsdfParams, EverySchemaEntryIsRead) {
    // Property sets that together set every parameter of every schema; building each must not
    // report an unread parameter (the host errors on those).
    std::vector<Properties> sets;
    {
        Properties p("diffuse", {});
        p.set_color("reflectance", Color(0.3f));
        sets.push_back(p);
    }
    {
        Properties p("conductor", {});
        p.set_color("eta", Color(0.2f));
        p.set_color("k", Color(3.f));
        p.set_string("ext_eta", "water");
        p.set_color("specular_reflectance", Color(0.9f));
        sets.push_back(p);
        Properties q("conductor", {});
        q.set_string("material", "Ag");
        q.set_float("ext_eta", 1.2);
        sets.push_back(q);
    }
    {
        Properties p("roughconductor", {});
        p.set_string("distribution", "GGX");
        p.set_float("alpha_u", 0.1);
        p.set_float("alpha_v", 0.3);
        p.set_bool("sample_visible", false);
        p.set_color("eta", Color(0.2f));
        p.set_color("k", Color(3.f));
        p.set_float("ext_eta", 1.0);
        p.set_color("specular_reflectance", Color(0.9f));
        sets.push_back(p);
        Properties q("roughconductor", {});
        q.set_float("alpha", 0.2);
        q.set_string("material", "W");
        sets.push_back(q);
    }
    {
        Properties p("dielectric", {});
        p.set_string("int_ior", "Fused Quartz");
        p.set_float("ext_ior", 1.0);
        p.set_color("specular_reflectance", Color(1.f));
        p.set_color("specular_transmittance", Color(0.9f));
        sets.push_back(p);
    }
    {
        Properties p("plastic", {});
        p.set_color("diffuse_reflectance", Color(0.5f));
        p.set_color("specular_reflectance", Color(1.f));
        p.set_float("int_ior", 1.6);
        p.set_string("ext_ior", "air");
        p.set_bool("nonlinear", true);
        sets.push_back(p);
    }
    {
        Properties p("roughplastic", {});
        p.set_string("distribution", "ggx");
        p.set_float("alpha", 0.3);
        p.set_bool("sample_visible", false);
        p.set_color("diffuse_reflectance", Color(0.5f));
        p.set_color("specular_reflectance", Color(1.f));
        p.set_float("int_ior", 1.6);
        p.set_string("ext_ior", "air");
        p.set_bool("nonlinear", true);
        sets.push_back(p);
    }
    {
        Properties p("thindielectric", {});
        p.set_string("int_ior", "water");
        p.set_float("ext_ior", 1.0);
        p.set_color("specular_reflectance", Color(1.f));
        p.set_color("specular_transmittance", Color(0.9f));
        sets.push_back(p);
    }
    sets.push_back(Properties("null", {}));

    std::set<std::string> used;
    for (const Properties& p : sets) {
        EXPECT_NO_THROW(build(p)) << p.plugin_type();
        for (const auto& e : p.entries()) used.insert(p.plugin_type() + "." + e.name);
    }
    for (const char* type : {"diffuse", "conductor", "roughconductor", "dielectric", "plastic",
                             "roughplastic", "thindielectric", "null", "twosided"}) {
        const femto::PluginDescriptor& desc = femto::find_plugin(femto::PluginKind::Bsdf, type);
        EXPECT_EQ(desc.kind, femto::PluginKind::Bsdf);
        for (const femto::ParamSpec& spec : desc.params) {
            EXPECT_NE(std::string(spec.doc), "") << type << "." << spec.name;
            if (std::string(type) == "twosided") continue;  // nested objects, tested above
            EXPECT_TRUE(used.count(std::string(type) + "." + spec.name))
                << "schema entry " << type << "." << spec.name << " is not exercised";
        }
    }
}

}  // namespace
