// The `btf` material: exact at the measured texels and directions, bilinear between texels,
// barycentric between directions within the closed form's variation, turning with the surface's
// u tangent, and located errors for bad parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "btf/synth.h"
#include "btf_test_util.h"
#include "femto/bsdf.h"
#include "femto/direction_mesh.h"
#include "femto/host.h"
#include "femto/properties.h"
#include "scene_util.h"

namespace {

using namespace femto;

btf::synth::Options options() { return femto::test::small_btf_a(); }

std::string synth_file(const btf::synth::Options& o, const std::string& name) {
    return femto::test::write_btf(o, "btf-material", name);
}

std::shared_ptr<Bsdf> make_btf(const std::string& file, double uv_scale = 1.0,
                               bool prefilter = false) {
    Properties p("btf", {});
    p.set_string("filename", file);
    p.set_float("uv_scale", uv_scale);
    p.set_bool("prefilter", prefilter);
    return std::static_pointer_cast<Bsdf>(create_object(PluginKind::Bsdf, "btf", p));
}

/// A hit on the plane z = 0 with the u tangent along `tangent` (world = shading frame).
Hit plane_hit(Vec2 uv, Vec3 tangent = Vec3(1, 0, 0)) {
    Hit hit;
    hit.uv = uv;
    hit.dpdu = tangent;
    hit.ng = Vec3(0, 0, 1);
    return hit;
}

/// uv of texel (x, y)'s centre: column x grows with u, row 0 is the top (v = 1).
Vec2 texel_uv(const btf::synth::Options& o, uint32_t x, uint32_t y) {
    return {(float(x) + 0.5f) / float(o.width), 1.f - (float(y) + 0.5f) / float(o.height)};
}

/// B recovered from eval(): f cos(theta_o) = B cos(theta_o) / pi.
Color reflectance(const Bsdf& bsdf, const Hit& hit, const Vec3& view, const Vec3& light) {
    return bsdf.eval(hit, view, light) * (kPi / light.z);
}

TEST(BtfMaterial, ExactAtTexelCentresAndSampledDirections) {
    const auto o = options();
    const auto bsdf = make_btf(synth_file(o, "exact.dfmf"));
    float worst = 0.f;
    for (uint32_t y = 0; y < o.height; ++y)
        for (uint32_t x = 0; x < o.width; ++x)
            for (uint32_t l = 1; l < 81; l += 9)
                for (uint32_t v = 2; v < 81; v += 11) {
                    const Color got = reflectance(*bsdf, plane_hit(texel_uv(o, x, y)),
                                                  o.directions[v], o.directions[l]);
                    const Color want = btf::synth::reference_value(o, x, y, l, v);
                    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(got[c] - want[c]));
                }
    // The file's float factors (1e-6), the directions' float angles and pi / cos: 1e-5.
    EXPECT_LE(worst, 1e-5f);
}

TEST(BtfMaterial, BilinearBetweenTexelsAndWrapping) {
    const auto o = options();
    const auto bsdf = make_btf(synth_file(o, "bilinear.dfmf"));
    const Vec3 view = o.directions[5], light = o.directions[40];
    auto at = [&](Vec2 uv) { return reflectance(*bsdf, plane_hit(uv), view, light); };
    auto texel = [&](uint32_t x, uint32_t y) {
        return btf::synth::reference_value(o, x, y, 40, 5);
    };
    // Halfway between columns 2 and 3 of row 1; and between the last and the first column.
    const Vec2 mid = {(3.f) / 8.f, 1.f - 1.5f / 4.f};
    const Vec2 edge = {0.f, 1.f - 1.5f / 4.f};
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(at(mid)[c], 0.5f * (texel(2, 1)[c] + texel(3, 1)[c]), 2e-5f);
        EXPECT_NEAR(at(edge)[c], 0.5f * (texel(7, 1)[c] + texel(0, 1)[c]), 2e-5f);
    }
    // uv_scale 3 repeats the texture every 1/3 in u and v.
    const auto tiled = make_btf(synth_file(o, "tiled.dfmf"), 3.0);
    const Vec2 uv = {0.1f, 0.2f};
    const Color a = reflectance(*tiled, plane_hit(uv), view, light);
    const Color b =
        reflectance(*tiled, plane_hit({uv.x + 1.f / 3.f, uv.y + 2.f / 3.f}), view, light);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 2e-5f);
}

Vec3 rotate_z(const Vec3& w, float angle) {
    const float c = std::cos(angle), s = std::sin(angle);
    return {c * w.x - s * w.y, s * w.x + c * w.y, w.z};
}

TEST(BtfMaterial, TurnsWithTheUTangent) {
    const auto o = options();
    const auto bsdf = make_btf(synth_file(o, "turn.dfmf"));
    const Vec2 uv = texel_uv(o, 3, 2);
    const Vec3 view = normalize(Vec3(0.3f, -0.2f, 0.9f)),
               light = normalize(Vec3(-0.5f, 0.1f, 0.7f));
    const Color base = reflectance(*bsdf, plane_hit(uv), view, light);
    for (float angle : {0.4f, 1.7f, 3.9f}) {
        // Rotating the tangent and both directions together changes nothing ...
        const Color turned = reflectance(*bsdf, plane_hit(uv, rotate_z(Vec3(2, 0, 0), angle)),
                                         rotate_z(view, angle), rotate_z(light, angle));
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(turned[c], base[c], 1e-4f);
    }
    // ... while the directions alone see BTF A's anisotropy.
    const Color other =
        reflectance(*bsdf, plane_hit(uv), rotate_z(view, 1.7f), rotate_z(light, 1.7f));
    EXPECT_GT(std::abs(other.r - base.r), 1e-2f);
    // A degenerate parameterization (dpdu = 0) falls back to the shading frame's s = x.
    const Color fallback = reflectance(*bsdf, plane_hit(uv, Vec3(0, 0, 0)), view, light);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(fallback[c], base[c], 1e-6f);
}

Vec3 random_direction(std::mt19937& rng, float max_theta) {
    std::uniform_real_distribution<float> u(0.f, 1.f);
    const float z = 1.f - u(rng) * (1.f - std::cos(max_theta)), phi = 2 * kPi * u(rng);
    const float r = std::sqrt(std::max(0.f, 1.f - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

TEST(BtfMaterial, InterpolationStaysWithinTheClosedFormsVariation) {
    // Between sampled directions the material is a convex combination of its neighbours: its
    // error against BTF A's closed form is at most the closed form's spread over the directions
    // it combines and the query, which all lie within one triangle of the sampling (at most
    // ~21 degrees across in UBO2003's 15-degree rings).
    const auto o = options();
    const auto bsdf = make_btf(synth_file(o, "interp.dfmf"));
    const btf::synth::HarmonicBtf closed(o.width, o.height);
    const DirectionMesh mesh(o.directions);
    std::mt19937 rng(11);
    const Vec2 uv = texel_uv(o, 5, 1);
    double worst_ratio = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const Vec3 light = random_direction(rng, 75.f * kPi / 180.f);
        const Vec3 view = random_direction(rng, 75.f * kPi / 180.f);
        const float got = reflectance(*bsdf, plane_hit(uv), view, light).g;
        const float want = closed.value(5, 1, light, view).g;
        float lo = want, hi = want;
        const auto wl = mesh.interpolate(light), wv = mesh.interpolate(view);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                if (wl.weight[i] <= 0.f || wv.weight[j] <= 0.f) continue;
                const Vec3 &dl = o.directions[wl.index[i]], &dv = o.directions[wv.index[j]];
                EXPECT_GT(dot(dl, light), std::cos(22.f * kPi / 180.f));
                EXPECT_GT(dot(dv, view), std::cos(22.f * kPi / 180.f));
                const float b = closed.value(5, 1, dl, dv).g;
                lo = std::min(lo, b);
                hi = std::max(hi, b);
            }
        EXPECT_LE(std::abs(got - want), hi - lo + 1e-5f);
        if (hi > lo) worst_ratio = std::max(worst_ratio, double(std::abs(got - want) / (hi - lo)));
    }
    std::printf("[btf] worst |interpolated - closed form| / spread: %.3f\n", worst_ratio);
}

TEST(BtfMaterial, SampleWeightIsEvalOverPdf) {
    const auto o = options();
    const auto bsdf = make_btf(synth_file(o, "weights.dfmf"));
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    const Hit hit = plane_hit({0.37f, 0.61f}, Vec3(0.6f, 0.8f, 0));
    const Vec3 wi = normalize(Vec3(0.2f, 0.4f, 0.8f));
    for (int i = 0; i < 200; ++i) {
        const BsdfSample s = bsdf->sample(hit, wi, u(rng), {u(rng), u(rng)});
        ASSERT_TRUE(s.valid());
        const Color f = bsdf->eval(hit, wi, s.wo);
        EXPECT_NEAR(s.pdf, bsdf->pdf(hit, wi, s.wo), 1e-6f);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.weight[c], f[c] / s.pdf, 1e-4f);
    }
    // Behind the surface: nothing.
    EXPECT_FALSE(bsdf->sample(hit, Vec3(0, 0, -1), 0.5f, {0.5f, 0.5f}).valid());
    EXPECT_TRUE(bsdf->eval(hit, wi, Vec3(0, 0.6f, -0.8f)).is_black());
}

TEST(BtfMaterial, PrefilteredWithoutAFootprintIsTheFinestLevel) {
    // Rays without a pixel footprint (after the first bounce) see level 0 unfiltered: for a
    // file with linear factors, the same values as the material without prefiltering.
    const auto o = options();
    const std::string file = synth_file(o, "nofootprint.dfmf");
    const auto plain = make_btf(file, 2.0), prefiltered = make_btf(file, 2.0, true);
    const Vec3 view = normalize(Vec3(0.2f, 0.1f, 0.9f)), light = normalize(Vec3(-0.4f, 0.3f, 0.8f));
    for (const Vec2 uv : {Vec2(0.1f, 0.2f), Vec2(0.77f, 0.41f)}) {
        const Color a = reflectance(*plain, plane_hit(uv), view, light);
        const Color b = reflectance(*prefiltered, plane_hit(uv), view, light);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 2e-6f);
    }
}

TEST(BtfMaterial, LightConeSelectsTheLightFilteredEntries) {
    // A camera hit whose light sample stands for a cone of light directions
    // (PixelFootprint::light_cone, e.g. an area light's extent) reads the hierarchy's entries
    // filtered over that cone: BTF A's closed form, cap means of half-angle 30 degrees over
    // lights (Funk-Hecke), at a texel centre and sampled directions, for a cone of 30 degrees
    // and for 15 degrees with scale_light = 2.
    const auto o = options();
    const std::string file = synth_file(o, "lightcone.dfmf");
    const btf::synth::HarmonicBtf closed(o.width, o.height);
    constexpr double kDeg = 3.14159265358979323846 / 180;
    for (const double scale_light : {1.0, 2.0}) {
        Properties p("btf", {});
        p.set_string("filename", file);
        p.set_bool("prefilter", true);
        p.set_float("scale_light", scale_light);
        const auto bsdf = std::static_pointer_cast<Bsdf>(create_object(PluginKind::Bsdf, "btf", p));
        double worst = 0, change = 0;
        for (const uint32_t x : {1u, 6u})
            for (uint32_t l = 3; l < 81; l += 13)
                for (uint32_t v = 2; v < 81; v += 17) {
                    Hit hit = plane_hit(texel_uv(o, x, 2));
                    hit.footprint.valid = true;  // no derivatives: level 0, no view cone
                    hit.footprint.light_cone = float(30 * kDeg / scale_light);
                    const Color got = reflectance(*bsdf, hit, o.directions[v], o.directions[l]);
                    hit.footprint.light_cone = 0;
                    const Color sharp = reflectance(*bsdf, hit, o.directions[v], o.directions[l]);
                    for (int c = 0; c < 3; ++c) {
                        double want = 0;
                        for (int k = 0; k < 3; ++k)
                            want += closed.spatial(c, k, x, 2) *
                                    btf::synth::HarmonicBtf::angular_cap_mean(
                                        k, o.directions[l], o.directions[v], 30 * kDeg, 0);
                        worst = std::max(worst, std::abs(got[c] - want));
                        change = std::max(change, double(std::abs(got[c] - sharp[c])));
                    }
                }
        // Float factors and pi / cos: as the unfiltered lookup, 1e-5.
        EXPECT_LT(worst, 1e-5) << "scale_light " << scale_light;
        EXPECT_GT(change, 1e-2) << "the cone must change the value";
    }
}

TEST(BtfMaterial, PrefilteredValuesAreNeverNegative) {
    // BTF B's V-grooves shadow their facets with hard edges in the light's direction; the
    // angular filter's low-order fit over-/undershoots there, and a filtered entry can come out
    // negative (the film then refuses the sample). The material reads the entries clamped at 0,
    // as a filtered non-negative function is.
    btf::synth::Options o;
    o.kind = btf::synth::Kind::VGroove;
    o.format = btf::Format::Dfmf;
    o.width = 4;
    o.height = 1;
    o.directions = btf::ubo2003_directions();
    const std::string file = synth_file(o, "vgroove-prefiltered.dfmf");
    Properties p("btf", {});
    p.set_string("filename", file);
    p.set_bool("prefilter", true);
    const auto bsdf = std::static_pointer_cast<Bsdf>(create_object(PluginKind::Bsdf, "btf", p));
    float lowest = 1.f;
    int evaluated = 0;
    for (const double ratio : {0.5, 2.0, 4.0})
        for (const float cone : {0.f, 0.3f, 0.8f})
            for (const float u : {0.05f, 0.3f, 0.55f, 0.8f})
                for (int i = 0; i < 12; ++i)
                    for (int j = 0; j < 12; ++j) {
                        Hit hit = plane_hit(Vec2(u, 0.5f));
                        hit.footprint.valid = true;
                        hit.footprint.duv_dx = Vec2(float(ratio / o.width), 0.f);
                        hit.footprint.light_cone = cone;
                        hit.footprint.dd_dx = Vec3(2 * cone, 0, 0);  // a view cone of `cone`
                        auto dir = [](int k, float azimuth) {
                            const float theta = (float(k) + 0.5f) / 12 * 1.5f;  // to 86 degrees
                            return Vec3(std::sin(theta) * std::cos(azimuth),
                                        std::sin(theta) * std::sin(azimuth), std::cos(theta));
                        };
                        const Vec3 light = dir(i, 0.3f * float(j)),
                                   view = dir(j, 2.f - 0.4f * float(i));
                        const Color b = reflectance(*bsdf, hit, view, light);
                        for (int c = 0; c < 3; ++c) lowest = std::min(lowest, b[c]);
                        ++evaluated;
                    }
    EXPECT_EQ(evaluated, 3 * 3 * 4 * 144);
    EXPECT_GE(lowest, 0.f);
}

TEST(BtfMaterial, BadParametersAreLocatedErrors) {
    const std::string good = synth_file(options(), "good.dfmf");
    auto scene = [](const std::string& params) {
        return femto::test::scene_xml("<shape type=\"rectangle\"><bsdf type=\"btf\">" + params +
                                      "</bsdf></shape>");
    };
    std::string e =
        femto::test::load_error(scene("<string name=\"filename\" value=\"/no/such.btf\"/>"));
    EXPECT_NE(e.find("no such file"), std::string::npos) << e;
    EXPECT_NE(e.find(":3:42:"), std::string::npos) << e;  // the filename parameter's location
    e = femto::test::load_error(scene("<string name=\"filename\" value=\"" + good +
                                      "\"/><float name=\"uv_scale\" value=\"0\"/>"));
    EXPECT_NE(e.find("uv_scale"), std::string::npos) << e;
    e = femto::test::load_error(scene("<string name=\"filename\" value=\"" + good +
                                      "\"/><float name=\"scale\" value=\"-1\"/>"));
    EXPECT_NE(e.find("scale"), std::string::npos) << e;
    e = femto::test::load_error(scene("<float name=\"uv_scale\" value=\"2\"/>"));
    EXPECT_NE(e.find("filename"), std::string::npos) << e;
    for (const auto& [params, name] :
         {std::pair{"<string name=\"filter\" value=\"sinc\"/>", "filter"},
          std::pair{"<string name=\"cone_angles\" value=\"5, 15\"/>", "cone_angles"},
          std::pair{"<string name=\"cone_angles\" value=\"0, x\"/>", "cone_angles"},
          std::pair{"<integer name=\"components\" value=\"0\"/>", "components"},
          std::pair{"<float name=\"scale_view\" value=\"0\"/>", "scale_view"},
          std::pair{"<string name=\"spatial_lookup\" value=\"ewa\"/>", "spatial_lookup"}}) {
        e = femto::test::load_error(
            scene("<string name=\"filename\" value=\"" + good + "\"/>" + params));
        EXPECT_NE(e.find(name), std::string::npos) << e;
    }
    const std::string bad = (femto::testing::temp_dir("btf-material") / "bad.btf").string();
    femto::test::write_text(bad, "!DFMF08FCR truncated");
    e = femto::test::load_error(scene("<string name=\"filename\" value=\"" + bad + "\"/>"));
    EXPECT_NE(e.find("bad.btf"), std::string::npos) << e;
    EXPECT_NE(e.find("meta data"), std::string::npos) << e;
}

}  // namespace
