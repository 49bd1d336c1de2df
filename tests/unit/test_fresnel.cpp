// Direct tests of the host's Fresnel terms and named-IOR tables (femto/fresnel.h) at values
// known in closed form. The Fresnel terms are also compared with independent formulas over
// many angles through the materials in test_bsdf_consistency.cpp; here: normal incidence,
// Brewster's angle, grazing incidence, total internal reflection, Snell's law, reciprocity,
// the conductor term's limits, and the name lookups.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "femto/error.h"
#include "femto/fresnel.h"
#include "femto/properties.h"

namespace {

using femto::Color;
using femto::ComplexIor;
using femto::fresnel_conductor;
using femto::fresnel_dielectric;
using femto::FresnelDielectric;

std::vector<std::string> split_names(const std::string& list) {
    std::vector<std::string> names;
    std::istringstream in(list);
    for (std::string name; std::getline(in, name, ',');)
        names.push_back(name.substr(name.find_first_not_of(' ')));
    return names;
}

TEST(FresnelDielectric, NormalIncidenceFromBothSides) {
    // R0 = ((eta - 1) / (eta + 1))^2 = 0.04 for eta = 1.5, the same from either side.
    const FresnelDielectric out = fresnel_dielectric(1.f, 1.5f);
    EXPECT_NEAR(out.r, 0.04f, 1e-7f);
    EXPECT_FLOAT_EQ(out.cos_t, -1.f);
    EXPECT_FLOAT_EQ(out.eta_it, 1.5f);
    EXPECT_FLOAT_EQ(out.eta_ti, 1.f / 1.5f);
    const FresnelDielectric in = fresnel_dielectric(-1.f, 1.5f);
    EXPECT_NEAR(in.r, 0.04f, 1e-7f);
    EXPECT_FLOAT_EQ(in.cos_t, 1.f);
    EXPECT_FLOAT_EQ(in.eta_it, 1.f / 1.5f);
    EXPECT_FLOAT_EQ(in.eta_ti, 1.5f);
}

TEST(FresnelDielectric, BrewsterAngle) {
    // At tan(theta_B) = eta the p-polarised part vanishes: R = r_s^2 / 2 with
    // r_s = (1 - eta^2) / (1 + eta^2).
    for (float eta : {1.333f, 1.5f, 2.419f}) {
        const float cos_b = 1.f / std::sqrt(1.f + eta * eta);
        const float rs = (1.f - eta * eta) / (1.f + eta * eta);
        EXPECT_NEAR(fresnel_dielectric(cos_b, eta).r, 0.5f * rs * rs, 1e-6f) << "eta " << eta;
    }
}

TEST(FresnelDielectric, SnellAndReciprocity) {
    const float eta = 1.5f;
    for (float cos_i : {0.05f, 0.3f, 0.6f, 0.9f, 0.99f}) {
        const FresnelDielectric out = fresnel_dielectric(cos_i, eta);
        const float sin_i = std::sqrt(1.f - cos_i * cos_i);
        ASSERT_LT(out.cos_t, 0.f);
        // sin_t = sin_i / eta.
        EXPECT_NEAR(std::sqrt(1.f - out.cos_t * out.cos_t), sin_i / eta, 1e-6f);
        // The reverse crossing, from inside along the refracted direction, sees the same R and
        // refracts back to cos_i.
        const FresnelDielectric back = fresnel_dielectric(out.cos_t, eta);
        EXPECT_NEAR(back.r, out.r, 1e-5f) << "cos_i " << cos_i;
        EXPECT_NEAR(back.cos_t, cos_i, 1e-5f);
        EXPECT_GT(out.r, 0.f);
        EXPECT_LT(out.r, 1.f);
    }
}

TEST(FresnelDielectric, GrazingTotalInternalReflectionAndIndexMatched) {
    EXPECT_EQ(fresnel_dielectric(0.f, 1.5f).r, 1.f);  // grazing
    // From inside glass, the critical cosine is sqrt(1 - 1 / eta^2) ~ 0.745.
    const FresnelDielectric tir = fresnel_dielectric(-0.5f, 1.5f);
    EXPECT_EQ(tir.r, 1.f);
    EXPECT_EQ(tir.cos_t, 0.f);
    EXPECT_LT(fresnel_dielectric(-0.8f, 1.5f).r, 1.f);
    // eta = 1: no reflection, straight through.
    for (float cos_i : {-0.7f, 0.2f, 1.f}) {
        const FresnelDielectric m = fresnel_dielectric(cos_i, 1.f);
        EXPECT_EQ(m.r, 0.f);
        EXPECT_NEAR(m.cos_t, -cos_i, 1e-7f);
    }
}

TEST(FresnelConductor, NormalIncidenceAndLimits) {
    // R0 = ((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2).
    for (auto [eta, k] : {std::pair{0.2f, 3.9f}, {1.66f, 9.22f}, {2.5f, 0.5f}, {0.05f, 2.f}}) {
        const float r0 = ((eta - 1) * (eta - 1) + k * k) / ((eta + 1) * (eta + 1) + k * k);
        EXPECT_NEAR(fresnel_conductor(1.f, eta, k), r0, 1e-6f) << eta << " + " << k << "i";
        EXPECT_NEAR(fresnel_conductor(0.f, eta, k), 1.f, 1e-6f);  // grazing
        // cos_i is clamped to [0, 1].
        EXPECT_EQ(fresnel_conductor(-0.5f, eta, k), fresnel_conductor(0.f, eta, k));
        EXPECT_EQ(fresnel_conductor(1.5f, eta, k), fresnel_conductor(1.f, eta, k));
    }
    // k = 0 is a dielectric seen from outside.
    for (float cos_i : {0.1f, 0.5f, 0.8f, 1.f})
        EXPECT_NEAR(fresnel_conductor(cos_i, 1.5f, 0.f), fresnel_dielectric(cos_i, 1.5f).r, 1e-6f)
            << "cos_i " << cos_i;
    // eta = k = 0: a perfect reflector.
    for (float cos_i : {0.f, 0.5f, 1.f}) EXPECT_EQ(fresnel_conductor(cos_i, 0.f, 0.f), 1.f);
}

TEST(FresnelConductor, RgbIsPerChannel) {
    const Color eta(0.2f, 0.9f, 1.1f), k(3.9f, 2.4f, 2.1f);
    for (float cos_i : {0.2f, 0.7f}) {
        const Color r = fresnel_conductor(cos_i, eta, k);
        for (int c = 0; c < 3; ++c) EXPECT_EQ(r[c], fresnel_conductor(cos_i, eta[c], k[c]));
    }
}

TEST(FresnelLookup, NamedIors) {
    EXPECT_EQ(femto::lookup_ior("vacuum"), 1.f);
    EXPECT_EQ(femto::lookup_ior("air"), 1.000277f);
    EXPECT_EQ(femto::lookup_ior("water"), 1.333f);
    EXPECT_EQ(femto::lookup_ior("bk7"), 1.5046f);
    EXPECT_EQ(femto::lookup_ior("diamond"), 2.419f);
    // Case-insensitive; the femto aliases.
    EXPECT_EQ(femto::lookup_ior("Fused Quartz"), 1.458f);
    EXPECT_EQ(femto::lookup_ior("BK7"), 1.5046f);
    EXPECT_EQ(femto::lookup_ior("glass"), femto::lookup_ior("bk7"));
    EXPECT_EQ(femto::lookup_ior("acrylic"), femto::lookup_ior("acrylic glass"));
    EXPECT_EQ(femto::lookup_ior("jelly"), std::nullopt);
    EXPECT_EQ(femto::lookup_ior(""), std::nullopt);
    EXPECT_EQ(femto::lookup_ior("water "), std::nullopt);

    const std::vector<std::string> names = split_names(femto::ior_names());
    ASSERT_EQ(names.size(), 25u);  // Mitsuba's 23 and the 2 aliases
    EXPECT_EQ(names.front(), "vacuum");
    EXPECT_EQ(names.back(), "glass");
    for (const std::string& name : names) {
        const std::optional<float> ior = femto::lookup_ior(name);
        ASSERT_TRUE(ior) << name;
        EXPECT_GE(*ior, 1.f) << name;
    }
}

TEST(FresnelLookup, ConductorPresets) {
    const std::optional<ComplexIor> au = femto::lookup_conductor_preset("Au");
    ASSERT_TRUE(au);
    EXPECT_EQ(au->eta, Color(0.1431189557f, 0.3749570432f, 1.4424785571f));
    EXPECT_EQ(au->k, Color(3.9831604247f, 2.3857207478f, 1.6032152899f));
    // Case-sensitive, as Mitsuba's; "none" is the plugins' ideal mirror, not a preset.
    EXPECT_FALSE(femto::lookup_conductor_preset("au"));
    EXPECT_FALSE(femto::lookup_conductor_preset("none"));
    EXPECT_FALSE(femto::lookup_conductor_preset("Unobtainium"));
    // The negative values of the RGB projection are clamped to zero.
    const std::optional<ComplexIor> alsb = femto::lookup_conductor_preset("AlSb");
    ASSERT_TRUE(alsb);
    EXPECT_EQ(alsb->eta, Color(0.f, 4.1427547893f, 4.6697691348f));
    EXPECT_EQ(alsb->k, Color(0.f, 0.0937665154f, 1.3007390124f));

    const std::vector<std::string> names = split_names(femto::conductor_preset_names());
    ASSERT_EQ(names.size(), 37u);
    EXPECT_EQ(names.front(), "a-C");
    EXPECT_EQ(names.back(), "W");
    for (const std::string& name : names) {
        const std::optional<ComplexIor> p = femto::lookup_conductor_preset(name);
        ASSERT_TRUE(p) << name;
        for (int c = 0; c < 3; ++c) {
            EXPECT_GE(p->eta[c], 0.f) << name;
            EXPECT_GE(p->k[c], 0.f) << name;
        }
        EXPECT_GT(p->eta.max_component() + p->k.max_component(), 0.f) << name;
    }
}

}  // namespace

// Indices past 1e4 (and non-finite ones) are located errors: the parameter sweep found that
// 1e30 overflowed the conductor and plastic Fresnel terms to NaN (dropped by the film with a
// warning) instead of being refused.
TEST(FresnelLookup, AbsurdIndicesAreLocatedErrors) {
    const femto::SourceLocation at{"ior.xml", 3, 5};
    for (const double v : {1e30, 1e4 * 1.001, HUGE_VAL, -1.0, 0.0, std::nan("")}) {
        SCOPED_TRACE(v);
        femto::Properties props("dielectric", {"ior.xml", 2, 1});
        props.set("int_ior", femto::Properties::Type::Float, v, at);
        try {
            femto::read_ior(props, "int_ior", "1.5");
            ADD_FAILURE() << "no error";
        } catch (const femto::SceneError& e) {
            EXPECT_EQ(e.location().line, 3) << e.what();
        }
    }
    femto::Properties fine("dielectric", {"ior.xml", 2, 1});
    fine.set("int_ior", femto::Properties::Type::Float, 1e4, at);
    EXPECT_EQ(femto::read_ior(fine, "int_ior", "1.5"), 1e4f);
    for (const char* name : {"eta", "k"}) {
        femto::Properties props("conductor", {"ior.xml", 2, 1});
        props.set(name, femto::Properties::Type::Color, femto::Color(1e30f), at);
        EXPECT_THROW(femto::read_conductor_ior(props), femto::SceneError) << name;
    }
}
