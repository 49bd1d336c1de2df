// Time-resolved rendering against physics: arrival times and amplitudes over a plane (camera
// and world time), energy conservation of the x-y-t film against the steady `path` render,
// the (eta - 1) d delay of a glass slab, and the `fluorescent` material (its sampling, colour
// transfer, lifetime and elastic lobe; its undelayed reflection and delayed, colour-shifted
// re-emission in a render).
//
// Tolerances:
//  - Arrival times are exact: every contribution's time is a sum of segment lengths in double
//    precision from float hit distances (relative rounding ~1e-7 on lengths < 10, i.e. < 1e-5
//    absolute). Scenes place the expected times at least 1e-3 inside a bin (bins are 5e-3 to
//    2e-2 wide), and a footprint's time range is widened by 1e-4 before it is mapped to bins.
//  - Monte Carlo means are compared within 4 standard errors (two-sided), the standard error
//    derived for each estimator where it is used (jitter of the pixel position, a binomial
//    choice, or the ratio estimator of a mean time over independent pixels).
//  - `path` and `transient_path` trace the same estimator (plugins/integrators/path) and draw the
//  same
//    random numbers per (pixel, sample) when roulette is off and the time window contains every
//    path: then the two steady images agree up to float summation order (see EnergyMatchesPath).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "cube_util.h"
#include "femto/bsdf.h"
#include "femto/film.h"
#include "femto/host.h"
#include "femto/properties.h"
#include "femto/random.h"
#include "femto/sensor.h"
#include "femto/time.h"
#include "scene_util.h"

using namespace femto;
using femto::test::Cube;
using femto::test::read_npy;
using femto::test::render_cube;
using femto::testing::bin_of;
using femto::testing::mean_arrival;
using femto::testing::MeanAndError;
using femto::testing::render_steady;

namespace {

const std::string kScenes = std::string(FEMTO_SOURCE_DIR) + "/scenes/";

LoadOptions defines(std::vector<std::pair<std::string, std::string>> d) {
    LoadOptions o;
    o.defines = std::move(d);
    return o;
}

std::string read_text(const std::string& path) {
    std::ifstream in(path);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// Replaces the first element that starts with `open` up to and including `close`.
std::string replace_element(const std::string& xml, const std::string& open,
                            const std::string& close, const std::string& with) {
    const size_t a = xml.find(open);
    EXPECT_NE(a, std::string::npos) << open;
    if (a == std::string::npos) return xml;
    const size_t b = xml.find(close, a);
    EXPECT_NE(b, std::string::npos) << close;
    return xml.substr(0, a) + with + xml.substr(b + close.size());
}

// ---------------------------------------------------------------------------------------------
// The fluorescent material on its own

std::shared_ptr<Bsdf> make_fluorescent(Color absorption, Color emission, double efficiency,
                                       double lifetime, Color reflectance = Color(0.f)) {
    Properties p("fluorescent", {});
    p.set_color("reflectance", reflectance);
    p.set_color("absorption", absorption);
    p.set_color("emission", emission);
    p.set_float("efficiency", efficiency);
    p.set_float("lifetime", lifetime);
    return std::static_pointer_cast<Bsdf>(create_object(PluginKind::Bsdf, "fluorescent", p));
}

double dot(const Color& a, const Color& b) {
    return double(a.r) * b.r + double(a.g) * b.g + double(a.b) * b.b;
}

}  // namespace

TEST(FluorescentMaterial, SampleWeightIsEvalOverPdf) {
    const auto bsdf = make_fluorescent({0, 0, 1}, {0, 1, 0}, 1, 1);
    ASSERT_TRUE(bsdf);
    EXPECT_TRUE(bsdf->has_vertex_event());
    EXPECT_EQ(bsdf->flags(), uint32_t(kBsdfDiffuseReflection));
    const Hit hit;
    Pcg32 rng(11, 3);
    for (int i = 0; i < 2000; ++i) {
        const Vec3 wi = normalize(
            Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, 0.05f + rng.next_float()));
        const BsdfSample s =
            bsdf->sample(hit, wi, rng.next_float(), {rng.next_float(), rng.next_float()});
        if (!s.valid()) continue;
        ASSERT_GT(s.wo.z, 0.f);
        const Color f = bsdf->eval(hit, wi, s.wo);
        const float pdf = bsdf->pdf(hit, wi, s.wo);
        // A Lambertian lobe: f cos = cos / pi, pdf = cos / pi (float rounding ~1e-7).
        EXPECT_NEAR(f.g, s.wo.z / M_PI, 1e-6);
        EXPECT_NEAR(pdf, s.wo.z / M_PI, 1e-6);
        EXPECT_NEAR(s.pdf, pdf, 1e-6 * pdf);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(s.weight[c], f[c] / pdf, 1e-5);
    }
    // Back side: nothing.
    EXPECT_FALSE(bsdf->sample(hit, Vec3(0, 0, -1), 0.5f, {0.3f, 0.3f}).valid());
    EXPECT_TRUE(bsdf->eval(hit, Vec3(0, 0, -1), Vec3(0, 0, 1)).is_black());
}

TEST(FluorescentMaterial, TransferIsAnEnergyConservingRankOneMatrix) {
    // Light direction: L_out = M L_in with M = efficiency * e a^T, e = emission / sum(emission).
    Pcg32 rng(5, 9);
    const Hit hit;
    for (int trial = 0; trial < 200; ++trial) {
        const Color a(rng.next_float(), rng.next_float(), rng.next_float());
        const Color em(rng.next_float() + 0.01f, rng.next_float(), rng.next_float());
        const double eff = rng.next_float();
        const auto bsdf = make_fluorescent(a, em, eff, 0.5);
        const double sum_e = double(em.r) + em.g + em.b;
        const Color L(rng.next_float(), rng.next_float(), rng.next_float());
        const double absorbed = dot(a, L);
        double ML[3];
        for (int c = 0; c < 3; ++c) ML[c] = eff * em[c] / sum_e * absorbed;
        // Without reflectance every vertex fluoresces: the event's transfer is M itself.
        ASSERT_TRUE(bsdf->has_vertex_event());
        const VertexEvent ev = bsdf->sample_vertex_event(hit, 0.5f);
        ASSERT_TRUE(ev.transfers);
        const Color out_c = ev.transfer * L;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(out_c[c], ML[c], 1e-6 * (1 + std::abs(ML[c])));
        // Energy (summed over channels): re-emitted = eff * absorbed <= in.
        const double out = double(out_c.r) + out_c.g + out_c.b;
        EXPECT_NEAR(out, eff * absorbed, 1e-6);
        EXPECT_LE(out, dot(Color(1.f), L) * (1 + 1e-6));
    }
    // Efficiency 1 and full absorption: all the energy comes back.
    const auto full = make_fluorescent({1, 1, 1}, {0.2f, 0.5f, 0.9f}, 1, 1);
    const Color L(0.3f, 1.7f, 0.25f);
    const Color back = full->sample_vertex_event(hit, 0.5f).transfer * L;
    EXPECT_NEAR(double(back.r) + back.g + back.b, 0.3 + 1.7 + 0.25, 1e-6);
}

TEST(FluorescentMaterial, DelayIsExponentialWithMeanLifetime) {
    const double tau = 2.5;
    const auto bsdf = make_fluorescent({0, 0, 1}, {0, 1, 0}, 1, tau);
    const Hit hit;
    Pcg32 rng(42, 1);
    const int n = 200000;
    double sum = 0, sum2 = 0;
    int beyond_tau = 0;
    for (int i = 0; i < n; ++i) {
        const double d = bsdf->sample_vertex_event(hit, rng.next_float()).delay;
        ASSERT_GE(d, 0.0);
        ASSERT_TRUE(std::isfinite(d));
        sum += d;
        sum2 += d * d;
        beyond_tau += d > tau;
    }
    const double mean = sum / n;
    const double sd = std::sqrt((sum2 - n * mean * mean) / (n - 1));
    EXPECT_NEAR(mean, tau, 4 * sd / std::sqrt(double(n)));
    EXPECT_NEAR(sd, tau, 0.02 * tau);  // sd of an exponential = its mean (SE of sd ~ tau/sqrt(n))
    // P(d > tau) = 1/e; binomial standard error.
    const double p = std::exp(-1.0);
    EXPECT_NEAR(double(beyond_tau) / n, p, 4 * std::sqrt(p * (1 - p) / n));
}

TEST(FluorescentMaterial, RejectsBadParameters) {
    Properties p("fluorescent", {});
    p.set_float("efficiency", 1.5);
    EXPECT_THROW(create_object(PluginKind::Bsdf, "fluorescent", p), SceneError);
    Properties q("fluorescent", {});
    q.set_color("emission", Color(0.f));
    EXPECT_THROW(create_object(PluginKind::Bsdf, "fluorescent", q), SceneError);
    Properties r("fluorescent", {});
    r.set_float("lifetime", -1);
    EXPECT_THROW(create_object(PluginKind::Bsdf, "fluorescent", r), SceneError);
}

TEST(FluorescentMaterial, RejectsReflectancePlusAbsorptionAboveOne) {
    // Energy conservation per channel: light is reflected, absorbed or lost.
    const std::string msg = femto::test::load_error(femto::test::scene_xml(
        "<shape type=\"rectangle\"><bsdf type=\"fluorescent\">\n"
        "<rgb name=\"reflectance\" value=\"0.2, 0.5, 0.1\"/>\n"
        "<rgb name=\"absorption\" value=\"0.3, 0.6, 0.9\"/></bsdf></shape>"));
    EXPECT_NE(msg.find("reflectance + absorption must not exceed 1"), std::string::npos) << msg;
    EXPECT_NE(msg.find("channel g"), std::string::npos) << msg;
    EXPECT_NE(msg.find("reflectance 0.5 + absorption 0.6"), std::string::npos) << msg;
    // The location is the reflectance entry (line 4 of the generated scene).
    EXPECT_NE(msg.find(":4:1:"), std::string::npos) << msg;
    // Exactly 1 (0.4 + 0.6 rounds above 1 in double from float inputs) is allowed.
    EXPECT_NO_THROW(load_scene_string(femto::test::scene_xml(
        "<shape type=\"rectangle\"><bsdf type=\"fluorescent\">"
        "<rgb name=\"reflectance\" value=\"0.4, 0.4, 0.4\"/>"
        "<rgb name=\"absorption\" value=\"0.6, 0.6, 0.6\"/></bsdf></shape>")));
    Properties q("fluorescent", {});
    q.set_color("reflectance", Color(1.5f, 0.f, 0.f));
    q.set_color("absorption", Color(0.f));
    EXPECT_THROW(create_object(PluginKind::Bsdf, "fluorescent", q), SceneError);
}

TEST(FluorescentMaterial, WithoutFluorescenceItIsExactlyDiffuse) {
    // No fluorescent energy (absorption 0, or efficiency 0): no vertex event, and eval, pdf and
    // sample compute diffuse's expressions, so the values are equal bit for bit.
    const Color r(0.1f, 0.5f, 0.08f);
    Properties dp("diffuse", {});
    dp.set_color("reflectance", r);
    const auto diffuse =
        std::static_pointer_cast<Bsdf>(create_object(PluginKind::Bsdf, "diffuse", dp));
    for (const auto& bsdf : {make_fluorescent(Color(0.f), {1, 0, 0}, 1, 1, r),
                             make_fluorescent({0.6f, 0.4f, 0.9f}, {1, 0, 0}, 0, 1, r)}) {
        EXPECT_FALSE(bsdf->has_vertex_event());
        const Hit hit;
        Pcg32 rng(7, 2);
        for (int i = 0; i < 500; ++i) {
            const Vec3 wi = normalize(
                Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.2f));
            const Vec2 u(rng.next_float(), rng.next_float());
            const BsdfSample a = bsdf->sample(hit, wi, 0.5f, u),
                             b = diffuse->sample(hit, wi, 0.5f, u);
            ASSERT_EQ(a.valid(), b.valid());
            if (!a.valid()) continue;
            EXPECT_EQ(a.pdf, b.pdf);
            for (int c = 0; c < 3; ++c) EXPECT_EQ(a.weight[c], b.weight[c]);
            const Color fa = bsdf->eval(hit, wi, a.wo), fb = diffuse->eval(hit, wi, a.wo);
            for (int c = 0; c < 3; ++c) EXPECT_EQ(fa[c], fb[c]);
            EXPECT_EQ(bsdf->pdf(hit, wi, a.wo), diffuse->pdf(hit, wi, a.wo));
        }
    }
}

TEST(FluorescentMaterial, EventsAverageToReflectancePlusFluorescence) {
    // With both parts the vertex is elastic (no delay, transfer diag(r) / p) with probability
    // p = sum(r) / (sum(r) + eff sum(a)), else fluorescent (Exp(tau) delay, transfer M / (1 - p)).
    // Averaged over u the transfer must be diag(r) + M (unbiasedness). u runs over the midpoints
    // of N equal strata, so averages are exact up to the one stratum straddling p (max |T| / N
    // ~ 3e-6) and float rounding; the mean delay's midpoint rule errs by ~tau ln(N) / N ~ 2e-5.
    const Color r(0.1f, 0.5f, 0.08f), a(0.6f, 0.4f, 0.9f), em(1.f, 0.25f, 0.f);
    const double eff = 0.9, tau = 1.5, sum_em = 1.25;
    const auto bsdf = make_fluorescent(a, em, eff, tau, r);
    ASSERT_TRUE(bsdf->has_vertex_event());
    const double sum_r = double(r.r) + r.g + r.b, sum_a = double(a.r) + a.g + a.b;
    const double p = sum_r / (sum_r + eff * sum_a);
    const Hit hit;
    const int N = 1 << 20;
    double T[3][3] = {}, delay_sum = 0;
    int elastic = 0;
    for (int k = 0; k < N; ++k) {
        const VertexEvent ev = bsdf->sample_vertex_event(hit, float((k + 0.5) / N));
        ASSERT_TRUE(ev.transfers);
        const ColorMatrix& t = ev.transfer;
        const bool diagonal = t.m[0][1] == 0 && t.m[0][2] == 0 && t.m[1][0] == 0 &&
                              t.m[1][2] == 0 && t.m[2][0] == 0 && t.m[2][1] == 0;
        if (diagonal) {  // elastic: at once, the reflectance over its probability
            ++elastic;
            ASSERT_EQ(ev.delay, 0.0);
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(t.m[c][c], r[c] / p, 1e-6);
        } else {
            ASSERT_GE(ev.delay, 0.0);
            ASSERT_TRUE(std::isfinite(ev.delay));
            delay_sum += ev.delay;
        }
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) T[i][j] += t.m[i][j];
    }
    EXPECT_NEAR(double(elastic) / N, p, 2.0 / N);
    EXPECT_NEAR(delay_sum / (N - elastic), tau, 1e-3 * tau);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const double expected = (i == j ? r[i] : 0.0) + eff * em[i] / sum_em * a[j];
            EXPECT_NEAR(T[i][j] / N, expected, 1e-4) << i << "," << j;
        }
}

// Time of flight over a plane, the glass-slab delay and fluorescence on a plane are checks of
// the integrator conformance matrix (femto/testing/integrator_conformance.h).

// ---------------------------------------------------------------------------------------------
// Energy: the transient cube summed over time is the steady `path` render

namespace {

struct EnergyCase {
    std::string scene;
    int max_depth;  // the scene's max_depth (set by the defines where the scene has one)
    std::vector<std::pair<std::string, std::string>> defines;
};

// The scene with `path` (roulette beyond max_depth, i.e. never) and an hdrfilm with the same
// size and reconstruction filter instead of transient_path and the transient film.
std::string as_steady_path(const std::string& xml, int max_depth) {
    const std::string depth = std::to_string(max_depth);
    const int rr = max_depth + 1;
    std::string out = replace_element(
        xml, "<integrator", "</integrator>",
        "<integrator type=\"path\"><integer name=\"max_depth\" value=\"" + depth +
            "\"/><integer name=\"rr_depth\" value=\"" + std::to_string(rr) + "\"/></integrator>");
    const size_t film = out.find("<film type=\"transient\">");
    const size_t rf = out.find("<rfilter type=\"", film);
    const std::string rfilter = out.substr(rf, out.find("/>", rf) + 2 - rf);
    return replace_element(out, "<film type=\"transient\">", "</film>",
                           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"$res\"/>"
                           "<integer name=\"height\" value=\"$res\"/>" +
                               rfilter + "</film>");
}

}  // namespace

TEST(Transient, EnergyMatchesPath) {
    // Both plugins are the same estimator (plugins/integrators/path) with the same options
    // (roulette off: `path` gets rr_depth = max_depth + 1, which is never reached; a transient path
    // only stops early when its time passes the window's end, which the windows below exclude: each
    // is longer than max_depth times the longest segment in its scene (bounded by the scene's
    // extent, times the glass index 1.52 in `spheres`) plus the longest camera segment; for
    // `fluorescent` the window also holds up to max_depth - 1 lifetime delays to a tail probability
    // below 1e-12). The samplers draw numbers per (seed, pixel, sample), so both integrators see
    // the same random numbers and produce the same contributions; only the films differ. The steady
    // images must then agree up to float rounding of the two accumulations (hdrfilm sums in double;
    // the cube sums per bin in float over <= 64 samples, relative error < 64 * 6e-8 ~ 4e-6): 1e-4
    // relative, plus 1e-6 absolute for dark pixels.
    const std::vector<EnergyCase> cases = {
        {"tof-plane", 2, {{"res", "16"}, {"spp", "16"}}},
        {"cornell-box",
         5,
         {{"res", "16"}, {"spp", "16"}, {"max_depth", "5"}, {"bins", "400"}}},  // 3.5..23.5
        {"spheres",
         4,
         {{"res", "16"},
          {"spp", "16"},
          {"max_depth", "4"},
          {"start", "0"},
          {"bin_width", "0.05"},
          {"bins", "1200"}}},  // 0..60 > 7.6 + 3 * 9 * 1.52 (camera segment, scene diagonal)
        {"fluorescent",
         4,
         {{"res", "16"},
          {"spp", "16"},
          {"max_depth", "4"},
          {"start", "0"},
          {"bin_width", "0.1"},
          {"bins", "1000"}}},  // 0..100: 3 delays of mean 1.5 exceed ~75 w.p. < 1e-18
    };
    for (const EnergyCase& c : cases) {
        SCOPED_TRACE(c.scene);
        const std::string path = kScenes + c.scene + "/scene.xml";
        const std::string xml = read_text(path);
        ASSERT_FALSE(xml.empty()) << path;
        auto transient = load_scene_string(xml, defines(c.defines), kScenes + c.scene);
        auto steady = load_scene_string(as_steady_path(xml, c.max_depth), defines(c.defines),
                                        kScenes + c.scene);
        femto::testing::expect_same_image(render_steady(*transient, 23), render_steady(*steady, 23),
                                          "transient", "path");
    }
}

// ---------------------------------------------------------------------------------------------
// Fluorescence in a render: delayed by the lifetime, re-emitted in the emission colour

namespace {

// A camera and a white point light (intensity I) at the centre of a sphere of radius R seen
// from inside. Every camera ray meets the sphere head-on at distance R and the light is R
// away along the normal, so the direct light arrives at camera time exactly 2R for every
// pixel, with radiance albedo * I / (pi R^2) (max_depth 2: direct light only).
constexpr double kSphereR = 1, kSphereI = 2, kTau = 0.5, kStart = 1.91, kWidth = 0.02;
constexpr int kBins = 400, kRes = 32;  // window 1.91 .. 9.91: 2R + 15.8 lifetimes

std::string sphere_scene(const std::string& bsdf) {
    return "<scene version=\"3.0.0\"><integrator type=\"transient_path\"><integer "
           "name=\"max_depth\" value=\"2\"/></integrator>"
           "<sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/>"
           "<transform name=\"to_world\"><lookat origin=\"0,0,0\" target=\"0,0,1\" "
           "up=\"0,1,0\"/></transform>"
           "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"16\"/></sampler>"
           "<film type=\"transient\"><integer name=\"width\" value=\"" +
           std::to_string(kRes) + "\"/><integer name=\"height\" value=\"" + std::to_string(kRes) +
           "\"/><float name=\"start\" value=\"" + std::to_string(kStart) +
           "\"/><float name=\"bin_width\" value=\"" + std::to_string(kWidth) +
           "\"/><integer name=\"bins\" value=\"" + std::to_string(kBins) +
           "\"/><rfilter type=\"box\"/></film></sensor>"
           "<shape type=\"sphere\"><float name=\"radius\" value=\"" +
           std::to_string(kSphereR) + "\"/><boolean name=\"flip_normals\" value=\"true\"/>" + bsdf +
           "</shape><emitter type=\"point\"><float name=\"intensity\" value=\"" +
           std::to_string(kSphereI) + "\"/></emitter></scene>";
}

const std::string kFluorescentBsdf =
    "<bsdf type=\"fluorescent\"><rgb name=\"absorption\" value=\"0,0,1\"/><rgb "
    "name=\"emission\" value=\"0,1,0\"/><float name=\"efficiency\" value=\"1\"/><float "
    "name=\"lifetime\" value=\"" +
    std::to_string(kTau) + "\"/></bsdf>";

// Expected mean bin centre of t0 + D, D ~ Exp(tau), on the window (the captured part only).
double expected_binned_mean(double t0, double tau) {
    double num = 0, den = 0;
    for (int t = 0; t < kBins; ++t) {
        const double lo = kStart + t * kWidth, hi = lo + kWidth;
        auto F = [&](double x) { return x <= t0 ? 0.0 : 1.0 - std::exp(-(x - t0) / tau); };
        const double p = F(hi) - F(lo);
        num += p * (lo + 0.5 * kWidth);
        den += p;
    }
    return num / den;
}

}  // namespace

TEST(Transient, FluorescenceArrivesOneLifetimeLater) {
    const double t0 = 2 * kSphereR;
    const int b0 = bin_of(kStart, kWidth, kBins, t0);
    ASSERT_EQ(b0, 4);  // t0 = 2 sits in the middle of bin 4 (1.99 .. 2.01)
    auto reference =
        load_scene_string(sphere_scene("<bsdf type=\"diffuse\"><float name=\"reflectance\" "
                                       "value=\"1\"/></bsdf>"));
    const Cube ref = render_cube(*reference, 31, "fluo-ref");
    auto fluorescent = load_scene_string(sphere_scene(kFluorescentBsdf));
    const Cube fl = render_cube(*fluorescent, 31, "fluo");

    // The reference: everything at t0, radiance I / (pi R^2) in every channel (exact: all
    // samples have the same value).
    const double L = kSphereI / (M_PI * kSphereR * kSphereR);
    for (int y = 0; y < kRes; ++y)
        for (int x = 0; x < kRes; ++x)
            for (int t = 0; t < kBins; ++t)
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(ref.at(y, x, t, c), t == b0 ? L : 0.0, 1e-5 * L);
    const MeanAndError r = mean_arrival(ref, kStart, kWidth);
    EXPECT_NEAR(r.mean, kStart + (b0 + 0.5) * kWidth, 1e-9);

    // The fluorescent sphere: the same energy (blue absorbed, efficiency 1; the importance of
    // all three channels summed), spread after t0 as an exponential of mean tau. The expected
    // mean of the bin centres is computed for this window (t0 + tau up to the binning and
    // the truncation at the window's end).
    const MeanAndError m = mean_arrival(fl, kStart, kWidth);
    const double expected = expected_binned_mean(t0, kTau);
    EXPECT_NEAR(expected, t0 + kTau, kWidth);  // what the window does to the mean
    EXPECT_GT(m.standard_error, 0.0);
    EXPECT_NEAR(m.mean - r.mean, expected - (kStart + (b0 + 0.5) * kWidth), 4 * m.standard_error)
        << "mean arrival " << m.mean << " vs reference " << r.mean << ", lifetime " << kTau;
    double total = 0;
    for (int y = 0; y < kRes; ++y)
        for (int x = 0; x < kRes; ++x)
            for (int t = 0; t < kBins; ++t) total += fl.energy(y, x, t);
    // Energy: all of I / (pi R^2) (blue) comes back, except the tail beyond the window
    // (exp(-7.91 / tau) ~ 1e-7), exactly per sample.
    EXPECT_NEAR(total / (kRes * kRes), L, 1e-4 * L);
}

TEST(Transient, FluorescenceIsReemittedInTheEmissionColour) {
    // Physics (Fig. 5.16): the sphere absorbs the blue third of the white light and re-emits
    // it as green: the camera must see (0, I / (pi R^2), 0), all of it in the green channel.
    auto fluorescent = load_scene_string(sphere_scene(kFluorescentBsdf));
    RenderOptions opt;
    opt.seed = 3;
    render(*fluorescent, opt);
    const auto img = fluorescent->sensor().film().steady_image();
    const double L = kSphereI / (M_PI * kSphereR * kSphereR);
    int wrong = 0;
    for (size_t p = 0; p < img.size() / 3; ++p) {
        const bool ok = std::abs(img[3 * p + 0]) <= 1e-6 * L &&
                        std::abs(img[3 * p + 1] - L) <= 1e-4 * L &&
                        std::abs(img[3 * p + 2]) <= 1e-6 * L;
        if (!ok && ++wrong <= 3)
            ADD_FAILURE() << "pixel " << p << ": (" << img[3 * p] << ", " << img[3 * p + 1] << ", "
                          << img[3 * p + 2] << "), expected (0, " << L << ", 0)";
    }
    EXPECT_EQ(wrong, 0);
}

TEST(Transient, FluorescentWithoutFluorescenceRendersLikeDiffuse) {
    // Without fluorescent energy (absorption 0, or efficiency 0) the material has no vertex
    // event and evaluates diffuse's expressions: the path tracer makes the same calls and draws
    // the same random numbers, so the images agree bit for bit, not only within noise. The
    // `fluorescent` scene at max_depth 4 exercises NEE, MIS and bounces off sphere and floor.
    const std::string xml = read_text(kScenes + "fluorescent/scene.xml");
    ASSERT_FALSE(xml.empty());
    const std::string r = "<rgb name=\"reflectance\" value=\"0.1, 0.5, 0.08\"/>";
    auto render_with = [&](const std::string& bsdf) {
        auto scene = load_scene_string(
            replace_element(xml, "<bsdf type=\"fluorescent\">", "</bsdf>", bsdf),
            defines({{"res", "16"}, {"spp", "16"}, {"max_depth", "4"}}), kScenes + "fluorescent");
        return render_steady(*scene, 7);
    };
    const auto diffuse = render_with("<bsdf type=\"diffuse\">" + r + "</bsdf>");
    const auto no_absorption = render_with("<bsdf type=\"fluorescent\">" + r +
                                           "<rgb name=\"absorption\" value=\"0, 0, 0\"/></bsdf>");
    const auto no_yield = render_with("<bsdf type=\"fluorescent\">" + r +
                                      "<rgb name=\"absorption\" value=\"0.6, 0.4, 0.9\"/>"
                                      "<float name=\"efficiency\" value=\"0\"/></bsdf>");
    ASSERT_EQ(diffuse.size(), no_absorption.size());
    ASSERT_EQ(diffuse.size(), no_yield.size());
    int differ_a = 0, differ_y = 0;
    double total = 0;
    for (size_t i = 0; i < diffuse.size(); ++i) {
        differ_a += diffuse[i] != no_absorption[i];
        differ_y += diffuse[i] != no_yield[i];
        total += diffuse[i];
    }
    EXPECT_GT(total, 0.0);
    EXPECT_EQ(differ_a, 0) << "absorption 0: values differing from `diffuse`";
    EXPECT_EQ(differ_y, 0) << "efficiency 0: values differing from `diffuse`";
}

TEST(Transient, ElasticReflectionArrivesAtOnceFluorescenceOneLifetimeLater) {
    // Fig. 5.16 in the sphere seen from inside (white point light at the centre, direct light
    // only): the material reflects r = (0, 0.6, 0.2) at once and absorbs a = (0.7, 0.3, 0.8),
    // re-emitting it as red (efficiency 0.8) after an Exp(tau) delay. Red is pure fluorescence,
    // green and blue pure elastic reflection. Every camera sample sees the same geometry, so
    // each is elastic with probability p = sum(r) / (sum(r) + eff sum(a)), contributing
    // (0, r.g, r.b) L / p at t0 = 2R, or fluorescent, contributing (eff sum(a) L / (1 - p), 0, 0)
    // at t0 + D, with L = I / (pi R^2).
    const double eff = 0.8, rg = 0.6, rb = 0.2, sum_a = 0.7 + 0.3 + 0.8;
    const std::string bsdf =
        "<bsdf type=\"fluorescent\"><rgb name=\"reflectance\" value=\"0, 0.6, 0.2\"/>"
        "<rgb name=\"absorption\" value=\"0.7, 0.3, 0.8\"/><rgb name=\"emission\" "
        "value=\"1, 0, 0\"/><float name=\"efficiency\" value=\"0.8\"/><float "
        "name=\"lifetime\" value=\"" +
        std::to_string(kTau) + "\"/></bsdf>";
    auto scene = load_scene_string(sphere_scene(bsdf));
    const Cube cube = render_cube(*scene, 37, "fluo-elastic");
    ASSERT_EQ(cube.T, kBins);
    const double L = kSphereI / (M_PI * kSphereR * kSphereR), t0 = 2 * kSphereR;
    const int b0 = bin_of(kStart, kWidth, kBins, t0), spp = 16;
    const double p = (rg + rb) / (rg + rb + eff * sum_a);
    const double red_per_sample = eff * sum_a * L / (1 - p), green_per_sample = rg * L / p;

    // Per pixel, exactly: green and blue only at t0 in the ratio r.g : r.b, nothing before t0;
    // the number of elastic samples k (from green) is an integer and the red (time-integrated)
    // is what the other spp - k samples carry. Tolerances are float rounding (the cube sums
    // in float, < 1e-5 relative), plus the red tail past the window (exp(-7.9 / tau) ~ 1e-7).
    double green = 0, blue = 0, red = 0;
    for (int y = 0; y < kRes; ++y)
        for (int x = 0; x < kRes; ++x) {
            double red_px = 0;
            for (int t = 0; t < kBins; ++t) {
                if (t != b0) {
                    ASSERT_EQ(cube.at(y, x, t, 1), 0.f) << x << "," << y << " bin " << t;
                    ASSERT_EQ(cube.at(y, x, t, 2), 0.f) << x << "," << y << " bin " << t;
                }
                if (t < b0) {
                    ASSERT_EQ(cube.at(y, x, t, 0), 0.f) << x << "," << y << " bin " << t;
                }
                red_px += cube.at(y, x, t, 0);
            }
            const double g = cube.at(y, x, b0, 1), b = cube.at(y, x, b0, 2);
            EXPECT_NEAR(b, g * rb / rg, 1e-5 * g);
            const double k = g * spp / green_per_sample;
            EXPECT_NEAR(k, std::round(k), 1e-3) << x << "," << y;
            EXPECT_NEAR(red_px, (spp - std::round(k)) / spp * red_per_sample,
                        1e-5 * red_per_sample);
            green += g;
            blue += b;
            red += red_px;
        }
    // The colour split over the image: N = res^2 spp independent binary choices, so the means
    // are r.g L (elastic) and eff sum(a) L (fluorescent) with binomial standard errors
    // r.g L sqrt((1 - p) / (p N)) and eff sum(a) L sqrt(p / ((1 - p) N)); 4 of them allowed.
    const double n = double(kRes) * kRes * spp, pixels = double(kRes) * kRes;
    EXPECT_NEAR(green / pixels, rg * L, 4 * rg * L * std::sqrt((1 - p) / (p * n)));
    EXPECT_NEAR(blue / pixels, rb * L, 4 * rb * L * std::sqrt((1 - p) / (p * n)));
    EXPECT_NEAR(red / pixels, eff * sum_a * L, 4 * eff * sum_a * L * std::sqrt(p / ((1 - p) * n)));

    // Timing: the elastic part at t0 exactly, the fluorescent part's mean arrival t0 + tau (up
    // to binning and the window, expected_binned_mean), within 4 standard errors of the ratio
    // estimator (mean_arrival).
    EXPECT_NEAR(mean_arrival(cube, kStart, kWidth, 1).mean, kStart + (b0 + 0.5) * kWidth, 1e-9);
    const MeanAndError m = mean_arrival(cube, kStart, kWidth, 0);
    EXPECT_GT(m.standard_error, 0.0);
    EXPECT_NEAR(m.mean, expected_binned_mean(t0, kTau), 4 * m.standard_error)
        << "fluorescent mean arrival " << m.mean << ", elastic " << t0 << ", lifetime " << kTau;
}

TEST(Transient, TwoSidedForwardsTheVertexEvent) {
    // `twosided` forwards its child's vertex event: seen from the front, the wrapped material
    // makes the same calls with the same random numbers as the material itself (bit-identical
    // images). Without forwarding the sphere would render white instead of green.
    auto plain = load_scene_string(sphere_scene(kFluorescentBsdf));
    auto wrapped =
        load_scene_string(sphere_scene("<bsdf type=\"twosided\">" + kFluorescentBsdf + "</bsdf>"));
    const auto a = render_steady(*plain, 13), b = render_steady(*wrapped, 13);
    ASSERT_EQ(a.size(), b.size());
    int differ = 0;
    for (size_t i = 0; i < a.size(); ++i) differ += a[i] != b[i];
    EXPECT_EQ(differ, 0);
    EXPECT_EQ(a[0], 0.f);  // red: absorbed blue comes back green only
    EXPECT_GT(a[1], 0.f);
}

TEST(Transient, VarianceAovMatchesTheSpreadAcrossSeeds) {
    // A box-pulse point light over a plane: each sample's contribution lands in a random bin,
    // so pixel-bin estimates are noisy. The variance AOV of one render must agree with the
    // variance of the same pixel-bin across independent renders (different seeds).
    const std::string xml =
        "<scene version=\"3.0.0\"><integrator type=\"transient_path\"><integer name=\"max_depth\" "
        "value=\"2\"/></integrator>"
        "<sensor type=\"orthographic\"><transform name=\"to_world\"><scale x=\"2\" y=\"2\"/>"
        "<lookat origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/></transform>"
        "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"4\"/></sampler>"
        "<film type=\"transient\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" "
        "value=\"16\"/><float name=\"start\" value=\"6\"/><float name=\"bin_width\" value=\"0.1\"/>"
        "<integer name=\"bins\" value=\"32\"/><string name=\"aovs\" value=\"variance, count\"/>"
        "<rfilter type=\"box\"/></film></sensor>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale "
        "value=\"10\"/></transform></shape>"
        "<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"0\" z=\"1.5\"/>"
        "<float name=\"intensity\" value=\"5\"/><string name=\"pulse\" value=\"box\"/>"
        "<float name=\"pulse_width\" value=\"1.5\"/></emitter></scene>";
    constexpr int K = 12;
    std::vector<Cube> cubes, variances;
    for (int k = 0; k < K; ++k) {
        auto scene = load_scene_string(xml);
        RenderOptions opt;
        opt.seed = 100 + k;
        const RenderStats stats = render(*scene, opt);
        RenderInfo info = make_render_info(*scene, opt, stats);
        info.write_npy = true;
        const auto dir = femto::test::temp_dir("variance-aov");
        const auto files = scene->sensor().film().write((dir / "v").string(), info);
        EXPECT_TRUE(std::filesystem::exists(dir / "v_count.npy"));
        cubes.push_back(read_npy((dir / "v.npy").string()));
        variances.push_back(read_npy((dir / "v_variance.npy").string()));
        std::filesystem::remove_all(dir);
    }
    const size_t n = cubes[0].data.size();
    // Empirical variance of each pixel-bin over the K renders, summed over pixel-bins; and
    // the AOV summed over pixel-bins, for each render.
    double empirical = 0, empirical_var = 0;
    for (size_t i = 0; i < n; ++i) {
        double m = 0, m2 = 0;
        for (const Cube& c : cubes) {
            m += c.data[i];
            m2 += double(c.data[i]) * c.data[i];
        }
        m /= K;
        const double s2 = (m2 - K * m * m) / (K - 1);
        empirical += s2;
        empirical_var += 2 * s2 * s2 / (K - 1);  // variance of a sample variance (normal cells)
    }
    std::vector<double> aov_sums;
    for (const Cube& v : variances)
        aov_sums.push_back(std::accumulate(v.data.begin(), v.data.end(), 0.0));
    const double aov = std::accumulate(aov_sums.begin(), aov_sums.end(), 0.0) / K;
    double spread = 0;
    for (double a : aov_sums) spread += (a - aov) * (a - aov);
    const double se_aov = std::sqrt(spread / (K - 1) / K);
    // Pixel-bins are independent estimates: the summed sample variances have the summed
    // variances 2 s^4 / (K - 1) of a chi-square with K - 1 degrees of freedom.
    const double se_emp = std::sqrt(empirical_var);
    ASSERT_GT(empirical, 0);
    EXPECT_NEAR(aov, empirical, 4 * std::sqrt(se_aov * se_aov + se_emp * se_emp))
        << "AOV " << aov << " (se " << se_aov << ") vs across seeds " << empirical << " (se "
        << se_emp << ")";
    std::printf("variance AOV %.6g (se %.3g), across %d seeds %.6g (se %.3g)\n", aov, se_aov, K,
                empirical, se_emp);
}
