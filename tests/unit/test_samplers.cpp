// Tests of the sampler plugins (independent, ldsampler, stratified): parameters, determinism,
// range, uniformity (chi-square), the (0,2)-net stratification of ldsampler, the strata of
// stratified, and their integration error against independent sampling.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "chi2.h"
#include "femto/host.h"
#include "femto/log.h"
#include "femto/random.h"
#include "femto/sampler.h"
#include "femto/sensor.h"
#include "femto/testing/render.h"
#include "scene_util.h"

namespace {

using femto::PluginKind;
using femto::Properties;
using femto::Sampler;
using femto::Vec2;

const char* const kSamplerTypes[] = {"independent", "ldsampler", "stratified"};

std::shared_ptr<Sampler> make_sampler(const std::string& type, int64_t sample_count,
                                      int64_t seed = 0, bool set_seed = false, bool jitter = true) {
    Properties props(type, {});
    props.set_int("sample_count", sample_count);
    if (set_seed) props.set_int("seed", seed);
    if (!jitter) props.set_bool("jitter", false);
    femto::ObjectPtr obj = femto::create_object(PluginKind::Sampler, type, props);
    EXPECT_TRUE(obj);
    EXPECT_EQ(obj->kind(), PluginKind::Sampler);
    return std::static_pointer_cast<Sampler>(obj);
}

// -- chi-square machinery ---------------------------------------------------------------------

/// p-value of a chi-square statistic with `dof` degrees of freedom (chi2.h's gamma function).
double chi2_pvalue(double chi2, int dof) { return femto_test::chi2_p_value(chi2, dof); }

/// Pearson's statistic of observed bin counts against a uniform expectation.
double chi2_uniform(const std::vector<int>& counts, double total) {
    const double expected = total / static_cast<double>(counts.size());
    double chi2 = 0.0;
    for (int c : counts) chi2 += (c - expected) * (c - expected) / expected;
    return chi2;
}

// Every chi-square test in this file; the significance level is split among them
// (Bonferroni), so that the whole file fails by chance with probability below 1%.
constexpr int kChi2Tests = 3 /*samplers*/ * 4 /*cases*/ + 2 /*stratified within strata*/;
constexpr double kChi2Alpha = 0.01 / kChi2Tests;

TEST(SamplerStats, IncompleteGammaMatchesKnownValues) {
    // chi^2 with 2 dof: p = exp(-x/2); with 1 dof, 3.841459 is the 5% critical value.
    for (double x : {0.1, 1.0, 4.0, 10.0, 40.0})
        EXPECT_NEAR(chi2_pvalue(x, 2), std::exp(-0.5 * x), 1e-12) << x;
    EXPECT_NEAR(chi2_pvalue(3.841459, 1), 0.05, 1e-6);
    EXPECT_NEAR(chi2_pvalue(255.0, 255), 0.4883, 2e-3);  // median ~ dof - 2/3
    EXPECT_NEAR(chi2_pvalue(310.457, 255), 0.01, 1e-3);  // 99th percentile of chi^2_255
}

// -- parameters -------------------------------------------------------------------------------

TEST(SamplerParams, SampleCountIsReadAndValidated) {
    for (const char* type : kSamplerTypes) {
        SCOPED_TRACE(type);
        EXPECT_EQ(make_sampler(type, 16)->sample_count(), 16u);
        EXPECT_EQ(make_sampler(type, 1)->sample_count(), 1u);
        {
            Properties props(type, {});
            auto s = std::static_pointer_cast<Sampler>(
                femto::create_object(PluginKind::Sampler, type, props));
            EXPECT_EQ(s->sample_count(), 4u);  // the default
        }
        for (int64_t bad : {int64_t(0), int64_t(-1), int64_t(-64), int64_t(1) << 40}) {
            Properties props(type, {});
            props.set_int("sample_count", bad);
            EXPECT_THROW(femto::create_object(PluginKind::Sampler, type, props), femto::SceneError)
                << bad;
        }
        Properties misspelt(type, {});
        misspelt.set_int("sample_cnt", 4);
        EXPECT_THROW(femto::create_object(PluginKind::Sampler, type, misspelt), femto::SceneError);
    }
}

TEST(SamplerParams, SchemaListsEveryParameter) {
    for (const char* type : kSamplerTypes) {
        SCOPED_TRACE(type);
        const femto::PluginDescriptor& d = femto::find_plugin(PluginKind::Sampler, type);
        EXPECT_EQ(d.kind, PluginKind::Sampler);
        EXPECT_EQ(std::string(d.type_name), type);
        std::set<std::string> names;
        for (const auto& p : d.params) {
            names.insert(p.name);
            EXPECT_GT(std::string(p.doc).size(), 0u);
        }
        std::set<std::string> expected{"sample_count", "seed"};
        if (std::string(type) == "stratified") expected.insert({"jitter", "dimension"});
        EXPECT_EQ(names, expected);
    }
}

// -- determinism and range --------------------------------------------------------------------

/// A mixed sequence of draws after start(seed, pixel, sample).
std::vector<float> draw(Sampler& s, uint64_t seed, uint64_t pixel, uint32_t sample) {
    s.start(seed, pixel, sample);
    std::vector<float> v;
    for (int i = 0; i < 4; ++i) {
        const Vec2 a = s.next_2d();
        v.push_back(a.x);
        v.push_back(a.y);
        v.push_back(s.next_1d());
    }
    return v;
}

TEST(SamplerDeterminism, SameTripleGivesSameNumbers) {
    for (const char* type : kSamplerTypes) {
        SCOPED_TRACE(type);
        auto s = make_sampler(type, 16);
        const std::vector<float> ref = draw(*s, 3, 1234, 5);
        // Other work in between, in another order, or on a clone must not matter.
        draw(*s, 3, 1235, 5);
        draw(*s, 9, 1, 0);
        s->start(3, 1234, 5);
        s->next_1d();
        EXPECT_EQ(draw(*s, 3, 1234, 5), ref);
        std::unique_ptr<Sampler> c = s->clone();
        EXPECT_EQ(c->sample_count(), 16u);
        EXPECT_EQ(draw(*c, 3, 1234, 5), ref);
        auto fresh = make_sampler(type, 16);
        EXPECT_EQ(draw(*fresh, 3, 1234, 5), ref);

        // Any change of pixel, sample, render seed or sampler seed changes the numbers.
        EXPECT_NE(draw(*s, 3, 1235, 5), ref);
        EXPECT_NE(draw(*s, 3, 1234, 6), ref);
        EXPECT_NE(draw(*s, 4, 1234, 5), ref);
        auto seeded = make_sampler(type, 16, 1, true);
        EXPECT_NE(draw(*seeded, 3, 1234, 5), ref);
        auto seeded2 = make_sampler(type, 16, 1, true);
        EXPECT_EQ(draw(*seeded2, 3, 1234, 5), draw(*seeded, 3, 1234, 5));
    }
}

// A pixel's samples one after another (as the renderer takes them; the ldsampler then reuses
// the pixel's slot seeds), past the slots it keeps and across advance_to() skips, give what a
// fresh sampler gives for each (pixel, sample) alone.
TEST(SamplerDeterminism, PixelMajorOrderGivesTheNumbersOfFreshSamplers) {
    const auto long_draw = [](Sampler& s, uint64_t pixel, uint32_t sample) {
        s.start(11, pixel, sample);
        std::vector<float> v;
        for (int i = 0; i < 100; ++i) {
            if (i == 30) s.advance_to(s.dimension() + 7);  // a gap in the slots
            const Vec2 a = s.next_2d();
            v.push_back(a.x);
            v.push_back(a.y);
            if (i % 3 == 0) v.push_back(s.next_1d());
        }
        return v;
    };
    for (const char* type : kSamplerTypes) {
        SCOPED_TRACE(type);
        auto s = make_sampler(type, 8);
        for (const uint64_t pixel : {5u, 5u, 6u, 5u})
            for (uint32_t sample = 0; sample < 8; ++sample) {
                auto fresh = make_sampler(type, 8);
                ASSERT_EQ(long_draw(*s, pixel, sample), long_draw(*fresh, pixel, sample))
                    << "pixel " << pixel << ", sample " << sample;
            }
    }
}

TEST(SamplerDeterminism, NeighbouringPixelsDiffer) {
    for (const char* type : kSamplerTypes) {
        SCOPED_TRACE(type);
        auto s = make_sampler(type, 4);
        std::set<std::vector<float>> seen;
        for (uint64_t pixel = 0; pixel < 1000; ++pixel) seen.insert(draw(*s, 0, pixel, 0));
        EXPECT_EQ(seen.size(), 1000u);
    }
}

TEST(SamplerRange, ValuesAreInUnitInterval) {
    for (const char* type : kSamplerTypes) {
        SCOPED_TRACE(type);
        auto s = make_sampler(type, 8);
        const uint64_t pixels[] = {0, 1, 77, 1ull << 32, ~0ull};
        const uint32_t samples[] = {0, 1, 7, 8, 1000, 0xffffffffu};
        float lo = 1.f, hi = 0.f;
        for (uint64_t p : pixels)
            for (uint32_t i : samples) {
                s->start(p * 31 + i, p, i);
                for (int d = 0; d < 64; ++d) {
                    const float a = s->next_1d();
                    const Vec2 b = s->next_2d();
                    for (float v : {a, b.x, b.y}) {
                        ASSERT_GE(v, 0.f);
                        ASSERT_LT(v, 1.f);
                        lo = std::min(lo, v);
                        hi = std::max(hi, v);
                    }
                }
            }
        EXPECT_LT(lo, 0.01f);
        EXPECT_GT(hi, 0.99f);
    }
}

// -- uniformity -------------------------------------------------------------------------------

/// 2-D histogram (bins x bins) of points produced by `gen(sampler)` for every (pixel, sample).
template <typename Gen>
double uniformity_pvalue(Sampler& s, int pixels, int spp, int bins, Gen gen) {
    std::vector<int> counts(bins * bins, 0);
    for (int p = 0; p < pixels; ++p)
        for (int i = 0; i < spp; ++i) {
            s.start(42, static_cast<uint64_t>(p), static_cast<uint32_t>(i));
            const Vec2 v = gen(s);
            const int bx = std::min(bins - 1, static_cast<int>(v.x * bins));
            const int by = std::min(bins - 1, static_cast<int>(v.y * bins));
            ++counts[by * bins + bx];
        }
    const double chi2 = chi2_uniform(counts, static_cast<double>(pixels) * spp);
    return chi2_pvalue(chi2, bins * bins - 1);
}

TEST(SamplerUniformity, ChiSquareOnTwoDimensionalBins) {
    for (const char* type : kSamplerTypes) {
        SCOPED_TRACE(type);
        auto s = make_sampler(type, 16);
        constexpr int kBins = 16;  // 256 cells, 64 points expected in each

        // 1. The first dimension pair, 16 samples in each of 1024 pixels.
        const double p1 =
            uniformity_pvalue(*s, 1024, 16, kBins, [](Sampler& x) { return x.next_2d(); });
        // 2. Two different pairs against each other (the x of pair 0 and of pair 2): catches
        //    correlation between the padded dimension pairs.
        const double p2 = uniformity_pvalue(*s, 1024, 16, kBins, [](Sampler& x) {
            const Vec2 a = x.next_2d();
            x.next_1d();
            const Vec2 b = x.next_2d();
            return Vec2(a.x, b.x);
        });
        // 3. Deep 1-D dimensions against each other (slots 20 and 21).
        const double p3 = uniformity_pvalue(*s, 1024, 16, kBins, [](Sampler& x) {
            for (int d = 0; d < 20; ++d) x.next_1d();
            const float a = x.next_1d();
            return Vec2(a, x.next_1d());
        });
        // 4. One sample in each of 16384 pixels: catches correlation between pixels.
        const double p4 =
            uniformity_pvalue(*s, 16384, 1, kBins, [](Sampler& x) { return x.next_2d(); });
        for (double p : {p1, p2, p3, p4}) EXPECT_GT(p, kChi2Alpha);
        std::printf(
            "[%s] chi-square p-values: pair %.3g, cross-pair %.3g, deep 1-D %.3g, "
            "across pixels %.3g (threshold %.2g)\n",
            type, p1, p2, p3, p4, kChi2Alpha);
    }
}

// -- ldsampler stratification -----------------------------------------------------------------

/// True when the points form a (0,k,2)-net in base 2 (2^k points; every elementary interval
/// of 2^a x 2^b cells, a + b = k, holds exactly one point).
::testing::AssertionResult is_02_net(const std::vector<Vec2>& pts, int k) {
    if (pts.size() != (size_t(1) << k))
        return ::testing::AssertionFailure() << "expected " << (1 << k) << " points";
    for (int a = 0; a <= k; ++a) {
        const int b = k - a;
        std::vector<int> counts(size_t(1) << k, 0);
        for (const Vec2& p : pts) {
            const int cx = static_cast<int>(std::ldexp(p.x, a));
            const int cy = static_cast<int>(std::ldexp(p.y, b));
            ++counts[(static_cast<size_t>(cy) << a) + cx];
        }
        for (size_t c = 0; c < counts.size(); ++c)
            if (counts[c] != 1)
                return ::testing::AssertionFailure()
                       << "elementary interval " << (c & ((1u << a) - 1)) << "," << (c >> a)
                       << " of the 2^" << a << " x 2^" << b << " grid holds " << counts[c]
                       << " points";
    }
    return ::testing::AssertionSuccess();
}

::testing::AssertionResult is_01_net(const std::vector<float>& xs, int k) {
    std::vector<int> counts(size_t(1) << k, 0);
    for (float x : xs) ++counts[static_cast<size_t>(std::ldexp(x, k))];
    for (size_t c = 0; c < counts.size(); ++c)
        if (counts[c] != 1)
            return ::testing::AssertionFailure()
                   << "interval " << c << " of 2^" << k << " holds " << counts[c] << " points";
    return ::testing::AssertionSuccess();
}

TEST(SamplerLd, EveryPixelIsAZeroTwoNet) {
    for (int k = 0; k <= 10; ++k) {
        const uint32_t n = 1u << k;
        auto s = make_sampler("ldsampler", n);
        for (uint64_t pixel : {uint64_t(0), uint64_t(1), uint64_t(517), uint64_t(1) << 40}) {
            SCOPED_TRACE("k=" + std::to_string(k) + " pixel=" + std::to_string(pixel));
            // The first and the second block of 2^k samples (progressive rendering beyond
            // sample_count continues the sequence), each on its own.
            for (uint32_t block = 0; block < 2; ++block) {
                std::vector<Vec2> pair0, pair2;
                std::vector<float> one1;
                for (uint32_t i = 0; i < n; ++i) {
                    s->start(11, pixel, block * n + i);
                    pair0.push_back(s->next_2d());
                    one1.push_back(s->next_1d());
                    pair2.push_back(s->next_2d());
                }
                EXPECT_TRUE(is_02_net(pair0, k));
                EXPECT_TRUE(is_01_net(one1, k));
                EXPECT_TRUE(is_02_net(pair2, k));
            }
        }
    }
}

// ldsampler's numbers, defined one slot at a time as its header comment states them (Burley's
// hash-based Owen scrambling of Sobol dimensions 0 and 1, the index shuffled per slot), and
// written here independently of the plugin, which computes eight slots at once in SIMD lanes.
// Locks every value bit for bit: a change of the sampler's numbers changes every image made
// with it, and must be a decision, not a side effect.
struct LdReference {
    static uint32_t reverse(uint32_t x) {
        uint32_t r = 0;
        for (int b = 0; b < 32; ++b) r |= ((x >> b) & 1u) << (31 - b);
        return r;
    }
    static uint32_t laine_karras(uint32_t x, uint32_t seed) {
        x ^= x * 0x3d20adeau;
        x += seed;
        x *= (seed >> 16) | 1u;
        x ^= x * 0x05526c56u;
        x ^= x * 0x53a22864u;
        return x;
    }
    static uint32_t owen(uint32_t x, uint32_t seed) {
        return reverse(laine_karras(reverse(x), seed));
    }
    static uint32_t sobol1(uint32_t index) {  // generator columns v_j = v_{j-1} ^ (v_{j-1} >> 1)
        uint32_t y = 0;
        for (uint32_t v = 1u << 31; index != 0; index >>= 1, v ^= v >> 1)
            if (index & 1u) y ^= v;
        return y;
    }
    static float unit(uint32_t x) { return float(x >> 8) * 0x1p-24f; }

    uint64_t pixel_seed;
    uint32_t index;
    uint64_t slot = 0;

    LdReference(uint64_t sampler_seed, uint64_t seed, uint64_t pixel, uint32_t sample)
        : pixel_seed(femto::hash_combine(femto::hash_combine(sampler_seed, seed), pixel)),
          index(sample) {}
    Vec2 next_2d() {
        const uint64_t h = femto::hash_combine(pixel_seed, slot++);
        const uint64_t g = femto::mix64(h ^ 0x2545f4914f6cdd1dULL);
        const uint32_t i = owen(index, uint32_t(h));  // the shuffled index
        return {unit(owen(reverse(i), uint32_t(h >> 32))), unit(owen(sobol1(i), uint32_t(g)))};
    }
};

TEST(SamplerLd, NumbersAreTheOneSlotDefinitionsBitForBit) {
    for (const int64_t sampler_seed : {int64_t(0), int64_t(77)}) {
        auto s = make_sampler("ldsampler", 16, sampler_seed, true);
        for (const uint64_t pixel : {uint64_t(0), uint64_t(3), uint64_t(1) << 40, ~uint64_t(0)})
            for (const uint32_t sample : {0u, 1u, 5u, 1000u, 0xffffffffu}) {
                SCOPED_TRACE("seed " + std::to_string(sampler_seed) + ", pixel " +
                             std::to_string(pixel) + ", sample " + std::to_string(sample));
                s->start(9, pixel, sample);
                LdReference ref(uint64_t(sampler_seed), 9, pixel, sample);
                // Draws of both kinds across batch boundaries, and skips within a batch, to
                // its end and far past it (advance_to, as BDPT's fixed layout uses it).
                for (int draw = 0; draw < 60; ++draw) {
                    if (draw == 11 || draw == 20 || draw == 40) {
                        const uint64_t to = s->dimension() + (draw == 11   ? 2
                                                              : draw == 20 ? 5
                                                                           : 1000);
                        s->advance_to(to);
                        ref.slot = to;
                    }
                    ASSERT_EQ(s->dimension(), ref.slot);
                    const Vec2 expected = ref.next_2d();
                    if (draw % 3 == 1) {
                        ASSERT_EQ(s->next_1d(), expected.x) << "draw " << draw;
                    } else {
                        const Vec2 u = s->next_2d();
                        ASSERT_EQ(u.x, expected.x) << "draw " << draw;
                        ASSERT_EQ(u.y, expected.y) << "draw " << draw;
                    }
                }
            }
    }
}

// The same, for the ways a sampler can be left midway through a batch of slots: a new start(),
// a clone() that goes on beside the original, skips to the batch's end, to the current
// dimension and backwards (no-ops), and slots past 2^64 (the count wraps, as before).
TEST(SamplerLd, NumbersAreTheOneSlotDefinitionsMidwayThroughABatch) {
    auto s = make_sampler("ldsampler", 16);
    const auto expect_pairs = [](Sampler& sampler, LdReference& ref, int n) {
        for (int draw = 0; draw < n; ++draw) {
            ASSERT_EQ(sampler.dimension(), ref.slot);
            const Vec2 expected = ref.next_2d(), u = sampler.next_2d();
            ASSERT_EQ(u.x, expected.x) << "slot " << ref.slot - 1;
            ASSERT_EQ(u.y, expected.y) << "slot " << ref.slot - 1;
        }
    };
    // Starts the sampler and its reference at (render seed 4, pixel, sample).
    const auto start = [&](uint64_t pixel, uint32_t sample) {
        s->start(4, pixel, sample);
        return LdReference(0, 4, pixel, sample);
    };
    // Every draw a pair (so each lane's y is checked), across three batches.
    LdReference all_pairs = start(21, 3);
    expect_pairs(*s, all_pairs, 24);
    // start() after three draws of a batch.
    LdReference first = start(21, 3);
    expect_pairs(*s, first, 3);
    LdReference second = start(22, 7);
    expect_pairs(*s, second, 12);
    // A clone taken midway through a batch, both going on.
    LdReference original = start(23, 1);
    expect_pairs(*s, original, 5);
    auto copy = s->clone();
    LdReference copied = original;
    expect_pairs(*copy, copied, 12);
    expect_pairs(*s, original, 12);
    // advance_to() to the batch's end from inside it, to the current dimension, backwards.
    LdReference skips = start(24, 2);
    expect_pairs(*s, skips, 3);
    s->advance_to(8);
    skips.slot = 8;
    expect_pairs(*s, skips, 2);
    s->advance_to(s->dimension());
    s->advance_to(1);
    expect_pairs(*s, skips, 9);
    // Slots counted past 2^64 wrap to 0, where the sequence starts again.
    LdReference wrap = start(25, 9);
    s->advance_to(~uint64_t(0) - 3);
    wrap.slot = ~uint64_t(0) - 3;
    expect_pairs(*s, wrap, 12);
}

TEST(SamplerLd, IndependentSamplerIsNotANet) {
    // Control for EveryPixelIsAZeroTwoNet: 64 random points almost never form a (0,6,2)-net.
    auto s = make_sampler("independent", 64);
    std::vector<Vec2> pts;
    for (uint32_t i = 0; i < 64; ++i) {
        s->start(11, 3, i);
        pts.push_back(s->next_2d());
    }
    EXPECT_FALSE(is_02_net(pts, 6));
}

// -- integration error ------------------------------------------------------------------------

/// Smooth, non-separable integrand on [0,1]^2 with integral e - 2.
double integrand(Vec2 p) { return p.x * std::exp(static_cast<double>(p.x) * p.y); }
const double kIntegral = std::exp(1.0) - 2.0;

/// Root-mean-square error of per-pixel estimates with `n` samples, over `pixels` pixels,
/// integrating over the dimension pair in slot `slot` (earlier slots drawn as next_1d()).
double rmse(const std::string& type, uint32_t n, int pixels, int slot) {
    auto s = make_sampler(type, n);
    double sq = 0.0;
    for (int p = 0; p < pixels; ++p) {
        double sum = 0.0;
        for (uint32_t i = 0; i < n; ++i) {
            s->start(5, static_cast<uint64_t>(p), i);
            for (int d = 0; d < slot; ++d) s->next_1d();
            sum += integrand(s->next_2d());
        }
        const double err = sum / n - kIntegral;
        sq += err * err;
    }
    return std::sqrt(sq / pixels);
}

TEST(SamplerLd, IntegrationErrorFarBelowIndependent) {
    // Standard deviation of the integrand under uniform sampling (by fine quadrature).
    double m1 = 0.0, m2 = 0.0;
    constexpr int kQ = 1000;
    for (int i = 0; i < kQ; ++i)
        for (int j = 0; j < kQ; ++j) {
            const double f = integrand(Vec2((i + 0.5f) / kQ, (j + 0.5f) / kQ));
            m1 += f;
            m2 += f * f;
        }
    m1 /= kQ * kQ;
    m2 /= kQ * kQ;
    ASSERT_NEAR(m1, kIntegral, 1e-6);
    const double sigma = std::sqrt(m2 - m1 * m1);

    // Expected rates: independent sampling has RMSE sigma / sqrt(N) (slope -1/2 in log-log);
    // Owen-scrambled (0,2)-nets have RMSE O(N^-3/2 sqrt(log N)) for smooth integrands
    // (Owen 1997), i.e. slope about -3/2 for power-of-two N.
    constexpr int kPixels = 256;
    for (int slot : {0, 3}) {
        SCOPED_TRACE("slot " + std::to_string(slot));
        const double ind16 = rmse("independent", 16, kPixels, slot);
        const double ind1024 = rmse("independent", 1024, kPixels, slot);
        const double ld16 = rmse("ldsampler", 16, kPixels, slot);
        const double ld256 = rmse("ldsampler", 256, kPixels, slot);
        const double ld1024 = rmse("ldsampler", 1024, kPixels, slot);
        const double ind_slope = std::log(ind1024 / ind16) / std::log(64.0);
        const double ld_slope = std::log(ld1024 / ld16) / std::log(64.0);
        std::printf(
            "slot %d: sigma %.4f; independent RMSE N=16 %.3e N=1024 %.3e (slope %.2f); "
            "ldsampler RMSE N=16 %.3e N=256 %.3e N=1024 %.3e (slope %.2f)\n",
            slot, sigma, ind16, ind1024, ind_slope, ld16, ld256, ld1024, ld_slope);

        // Independent: sigma / sqrt(N) (256 pixels estimate the RMSE to ~5%).
        EXPECT_NEAR(ind16, sigma / 4.0, 0.2 * sigma / 4.0);
        EXPECT_NEAR(ind1024, sigma / 32.0, 0.2 * sigma / 32.0);
        EXPECT_NEAR(ind_slope, -0.5, 0.1);
        // ldsampler: already better at 16 samples, orders of magnitude better at 1024.
        EXPECT_LT(ld16, ind16 / 3.0);
        EXPECT_LT(ld1024, ind1024 / 50.0);
        EXPECT_LT(ld_slope, -1.2);
    }
}

// -- stratified -------------------------------------------------------------------------------

/// The draws of sample `sample` of `pixel` in a fixed pattern of dimensions: 2-D, 1-D, 2-D,
/// 1-D, 2-D (the pattern of a camera sample followed by a few bounces).
struct StratifiedDraws {
    std::vector<Vec2> two_d;
    std::vector<float> one_d;
};
StratifiedDraws draw_pattern(Sampler& s, uint64_t seed, uint64_t pixel, uint32_t sample) {
    s.start(seed, pixel, sample);
    StratifiedDraws d;
    d.two_d.push_back(s.next_2d());
    d.one_d.push_back(s.next_1d());
    d.two_d.push_back(s.next_2d());
    d.one_d.push_back(s.next_1d());
    d.two_d.push_back(s.next_2d());
    return d;
}

/// True when the N values hold exactly one value in each stratum [k/N, (k+1)/N).
::testing::AssertionResult one_per_stratum(const std::vector<float>& xs) {
    const size_t n = xs.size();
    std::vector<int> counts(n, 0);
    for (float x : xs) ++counts[std::min(n - 1, static_cast<size_t>(double(x) * double(n)))];
    for (size_t k = 0; k < n; ++k)
        if (counts[k] != 1)
            return ::testing::AssertionFailure()
                   << "stratum " << k << " of " << n << " holds " << counts[k] << " values";
    return ::testing::AssertionSuccess();
}

/// True when the side^2 points hold exactly one point in each cell of the side x side grid.
::testing::AssertionResult one_per_cell(const std::vector<Vec2>& pts, int side) {
    std::vector<int> counts(size_t(side) * size_t(side), 0);
    for (const Vec2& p : pts) {
        const int cx = std::min(side - 1, static_cast<int>(double(p.x) * side));
        const int cy = std::min(side - 1, static_cast<int>(double(p.y) * side));
        ++counts[size_t(cy) * size_t(side) + size_t(cx)];
    }
    for (size_t c = 0; c < counts.size(); ++c)
        if (counts[c] != 1)
            return ::testing::AssertionFailure()
                   << "cell (" << c % size_t(side) << ", " << c / size_t(side) << ") of " << side
                   << " x " << side << " holds " << counts[c] << " points";
    return ::testing::AssertionSuccess();
}

/// Checks that samples [block * N, (block + 1) * N) of `pixel` are stratified in every
/// dimension of draw_pattern(), with or without jitter.
void expect_stratified_block(Sampler& s, int side, uint64_t pixel, uint32_t block) {
    const uint32_t n = uint32_t(side * side);
    std::vector<std::vector<Vec2>> two_d(3);
    std::vector<std::vector<float>> one_d(2);
    for (uint32_t i = 0; i < n; ++i) {
        const StratifiedDraws d = draw_pattern(s, 11, pixel, block * n + i);
        for (size_t k = 0; k < 3; ++k) two_d[k].push_back(d.two_d[k]);
        for (size_t k = 0; k < 2; ++k) one_d[k].push_back(d.one_d[k]);
    }
    for (const auto& dim : two_d) EXPECT_TRUE(one_per_cell(dim, side));
    for (const auto& dim : one_d) EXPECT_TRUE(one_per_stratum(dim));
}

TEST(SamplerStratified, EveryStratumHoldsOneSamplePerPixel) {
    // N = 16 (4 x 4) is the case of interest; the other squares check the index arithmetic.
    for (int side : {4, 1, 2, 3, 5, 8, 13}) {
        auto s = make_sampler("stratified", side * side);
        ASSERT_EQ(s->sample_count(), uint32_t(side * side));
        for (uint64_t pixel : {uint64_t(0), uint64_t(1), uint64_t(517), uint64_t(1) << 40}) {
            // The first block of N samples and the next (indices past sample_count, as
            // progressive rendering or --spp draw them) are each stratified on their own.
            for (uint32_t block : {0u, 1u}) {
                SCOPED_TRACE("n=" + std::to_string(side) + " pixel=" + std::to_string(pixel) +
                             " block=" + std::to_string(block));
                expect_stratified_block(*s, side, pixel, block);
            }
        }
    }
}

TEST(SamplerStratified, EachDimensionHasItsOwnPermutation) {
    // Strata of different dimensions (and of different pixels) are not visited in the same
    // order: the stratum index sequences over a pixel's 16 samples differ.
    auto s = make_sampler("stratified", 16);
    std::set<std::vector<int>> orders;
    for (uint64_t pixel = 0; pixel < 8; ++pixel) {
        std::vector<std::vector<int>> per_dim(5);
        for (uint32_t i = 0; i < 16; ++i) {
            const StratifiedDraws d = draw_pattern(*s, 3, pixel, i);
            for (size_t k = 0; k < 3; ++k)
                per_dim[k].push_back(int(d.two_d[k].y * 4) * 4 + int(d.two_d[k].x * 4));
            for (size_t k = 0; k < 2; ++k) per_dim[3 + k].push_back(int(d.one_d[k] * 16));
        }
        for (auto& order : per_dim) orders.insert(order);
    }
    EXPECT_EQ(orders.size(), 40u);  // 8 pixels x 5 dimensions, all different
}

TEST(SamplerStratified, UniformWithinStrata) {
    // Where a value falls inside its stratum: (x N) mod 1 for 1-D, (x n, y n) mod 1 for 2-D.
    // Over 4096 pixels x 16 samples they must be uniform (the strata alone are checked above).
    auto s = make_sampler("stratified", 16);
    constexpr int kPixels = 4096, kBins = 16;
    std::vector<int> counts_1d(kBins * kBins, 0), counts_2d(kBins * kBins, 0);
    auto bin = [](double v) { return std::min(kBins - 1, static_cast<int>(v * kBins)); };
    for (int p = 0; p < kPixels; ++p)
        for (uint32_t i = 0; i < 16; ++i) {
            s->start(42, uint64_t(p), i);
            const Vec2 a = s->next_2d();
            const float b = s->next_1d(), c = s->next_1d();
            const double ax = a.x * 4.0, ay = a.y * 4.0, b16 = b * 16.0, c16 = c * 16.0;
            ++counts_2d[bin(ay - std::floor(ay)) * kBins + bin(ax - std::floor(ax))];
            ++counts_1d[bin(c16 - std::floor(c16)) * kBins + bin(b16 - std::floor(b16))];
        }
    const double total = double(kPixels) * 16;
    const double p2 = chi2_pvalue(chi2_uniform(counts_2d, total), kBins * kBins - 1);
    const double p1 = chi2_pvalue(chi2_uniform(counts_1d, total), kBins * kBins - 1);
    std::printf(
        "[stratified] offsets within strata: chi-square p 2-D %.3g, 1-D pair %.3g "
        "(threshold %.2g)\n",
        p2, p1, kChi2Alpha);
    EXPECT_GT(p2, kChi2Alpha);
    EXPECT_GT(p1, kChi2Alpha);
}

TEST(SamplerStratified, WithoutJitterEveryValueIsAStratumCentre) {
    auto s = make_sampler("stratified", 16, 0, false, /*jitter=*/false);
    for (uint64_t pixel : {uint64_t(0), uint64_t(9), uint64_t(1) << 33}) {
        for (uint32_t i = 0; i < 32; ++i) {
            const StratifiedDraws d = draw_pattern(*s, 7, pixel, i);
            for (const Vec2& v : d.two_d)
                for (float x : {v.x, v.y}) {
                    const float k = std::floor(x * 4.f);
                    EXPECT_EQ(x, (k + 0.5f) / 4.f) << x;
                }
            for (float x : d.one_d) EXPECT_EQ(x, (std::floor(x * 16.f) + 0.5f) / 16.f) << x;
        }
        // Still one value per stratum.
        expect_stratified_block(*s, 4, pixel, 0);
    }

    // One sample per pixel: every number is the centre of the unit square or interval, in
    // every pixel, sample (also past sample_count) and dimension.
    auto one = make_sampler("stratified", 1, 0, false, /*jitter=*/false);
    for (uint64_t pixel = 0; pixel < 100; ++pixel)
        for (uint32_t i : {0u, 1u, 5u}) {
            one->start(pixel * 13, pixel, i);
            for (int k = 0; k < 10; ++k) {
                const Vec2 v = one->next_2d();
                EXPECT_EQ(v.x, 0.5f);
                EXPECT_EQ(v.y, 0.5f);
                EXPECT_EQ(one->next_1d(), 0.5f);
            }
        }
}

TEST(SamplerStratified, SameNumbersWhateverOrderPixelsAreStartedIn) {
    constexpr int kPixels = 64;
    constexpr uint32_t kSamples = 16;
    auto forward = make_sampler("stratified", kSamples);
    std::vector<std::vector<float>> ref(size_t(kPixels) * kSamples);
    for (int p = 0; p < kPixels; ++p)
        for (uint32_t i = 0; i < kSamples; ++i)
            ref[size_t(p) * kSamples + i] = draw(*forward, 21, uint64_t(p), i);

    // A fresh sampler and a clone of a used one, visiting the (pixel, sample) pairs backwards
    // and interleaved (sample-major), as threads taking tiles in another order would.
    auto backward = make_sampler("stratified", kSamples);
    std::unique_ptr<Sampler> clone = forward->clone();
    for (int p = kPixels - 1; p >= 0; --p)
        for (uint32_t i = kSamples; i-- > 0;)
            EXPECT_EQ(draw(*backward, 21, uint64_t(p), i), ref[size_t(p) * kSamples + i]);
    for (uint32_t i = 0; i < kSamples; ++i)
        for (int p = 0; p < kPixels; p += 1 + int(i % 3)) {
            clone->start(99, uint64_t(p), i);  // unrelated work in between
            clone->next_2d();
            EXPECT_EQ(draw(*clone, 21, uint64_t(p), i), ref[size_t(p) * kSamples + i]);
        }
}

TEST(SamplerStratified, NonSquareCountRoundsUpWithAWarning) {
    // Mitsuba 3 (and 0.6) round up to the next perfect square and warn.
    const std::pair<int64_t, uint32_t> cases[] = {{10, 16}, {2, 4}, {17, 25}, {99, 100}};
    for (const auto& [given, used] : cases) {
        SCOPED_TRACE(given);
        const int before = femto::warning_count();
        ::testing::internal::CaptureStderr();
        auto s = make_sampler("stratified", given);
        const std::string err = ::testing::internal::GetCapturedStderr();
        EXPECT_EQ(femto::warning_count() - before, 1);
        EXPECT_NE(err.find("rounding " + std::to_string(given) + " up to " + std::to_string(used)),
                  std::string::npos)
            << err;
        EXPECT_EQ(s->sample_count(), used);
    }
    // 10 -> 16: the 16 samples form the 4 x 4 strata.
    auto ten = make_sampler("stratified", 10);
    expect_stratified_block(*ten, 4, 3, 0);

    // Perfect squares are used as given, silently.
    const int before = femto::warning_count();
    for (int64_t square :
         {int64_t(1), int64_t(4), int64_t(9), int64_t(16), int64_t(1024), int64_t(65535) * 65535})
        EXPECT_EQ(make_sampler("stratified", square)->sample_count(), uint32_t(square));
    EXPECT_EQ(femto::warning_count(), before);

    // A count whose square does not fit 32 bits is refused.
    Properties props("stratified", {});
    props.set_int("sample_count", 65535ll * 65535ll + 1);
    EXPECT_THROW(femto::create_object(PluginKind::Sampler, "stratified", props), femto::SceneError);
}

TEST(SamplerStratified, IntegrationErrorFarBelowIndependent) {
    // Jittered sampling of a smooth 2-D integrand has RMSE O(N^-1) against independent
    // sampling's sigma / sqrt(N): at N = 64, x e^(xy) gives about 1/7 of the error.
    constexpr int kPixels = 256;
    for (int slot : {0, 3}) {
        SCOPED_TRACE("slot " + std::to_string(slot));
        const double ind64 = rmse("independent", 64, kPixels, slot);
        const double st16 = rmse("stratified", 16, kPixels, slot);
        const double st64 = rmse("stratified", 64, kPixels, slot);
        const double st1024 = rmse("stratified", 1024, kPixels, slot);
        const double st_slope = std::log(st1024 / st16) / std::log(64.0);
        std::printf(
            "slot %d: RMSE independent N=64 %.3e; stratified N=16 %.3e N=64 %.3e N=1024 %.3e "
            "(slope %.2f)\n",
            slot, ind64, st16, st64, st1024, st_slope);
        EXPECT_LT(st64, ind64 / 4.0);
        EXPECT_NEAR(st_slope, -1.0, 0.15);
    }
    // The same for the integral of x y over the unit square (1/4) from the first 2-D
    // dimension, as a camera sample's position in the pixel is drawn.
    auto xy_rmse = [](const std::string& type) {
        auto s = make_sampler(type, 64);
        double sq = 0;
        for (int p = 0; p < kPixels; ++p) {
            double sum = 0;
            for (uint32_t i = 0; i < 64; ++i) {
                s->start(5, uint64_t(p), i);
                const Vec2 v = s->next_2d();
                sum += double(v.x) * v.y;
            }
            sq += (sum / 64 - 0.25) * (sum / 64 - 0.25);
        }
        return std::sqrt(sq / kPixels);
    };
    const double ind = xy_rmse("independent"), st = xy_rmse("stratified");
    std::printf("x y: RMSE independent %.3e, stratified %.3e (ratio %.1f)\n", ind, st, ind / st);
    EXPECT_LT(st, ind / 4.0);
}

/// An 8 x 8 orthographic view of [-1, 1]^2 (box filter, 1 spp, `stratified` with `jitter` or
/// not) of 64 emitting disks (radiance 1) on a black background, one under each pixel centre,
/// of radius 1/10 of a pixel. A pixel is 1 if its ray passed within 1/10 pixel of its centre,
/// else 0. (The pixel centres are symmetric about the origin, so however the camera mirrors
/// the image, each lies over a disk centre.)
std::string centre_check_scene(bool jitter) {
    std::string xml =
        "<scene version=\"3.0.0\"><integrator type=\"path\"/><sensor type=\"orthographic\">"
        "<transform name=\"to_world\"><lookat origin=\"0,0,5\" target=\"0,0,0\" "
        "up=\"0,1,0\"/></transform><sampler type=\"stratified\"><integer name=\"sample_count\" "
        "value=\"1\"/><boolean name=\"jitter\" value=\"" +
        std::string(jitter ? "true" : "false") +
        "\"/></sampler><film type=\"hdrfilm\"><integer name=\"width\" value=\"8\"/><integer "
        "name=\"height\" value=\"8\"/><rfilter type=\"box\"/></film></sensor>";
    constexpr double kPixel = 2.0 / 8;
    for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j)
            xml += "<shape type=\"disk\"><transform name=\"to_world\"><scale value=\"" +
                   femto::test::xml_number(0.1 * kPixel) + "\"/><translate x=\"" +
                   femto::test::xml_number(-1 + (i + 0.5) * kPixel) + "\" y=\"" +
                   femto::test::xml_number(-1 + (j + 0.5) * kPixel) +
                   "\"/></transform><bsdf type=\"diffuse\"><float name=\"reflectance\" "
                   "value=\"0\"/></bsdf><emitter type=\"area\"/></shape>";
    return xml + "</scene>";
}

TEST(SamplerStratified, WithoutJitterCameraRaysPassThroughPixelCentres) {
    int seen_through[2] = {0, 0};
    for (bool jitter : {false, true}) {
        auto scene = femto::load_scene_string(centre_check_scene(jitter));
        ASSERT_EQ(scene->sensor().sampler().type_name(), "stratified");
        const std::vector<float> img = femto::testing::render_steady(*scene, 3);
        ASSERT_EQ(img.size(), 8u * 8u * 3u);
        for (size_t i = 0; i < img.size(); i += 3) {
            // Every sample sees either a disk (1) or the background (0), nothing between.
            EXPECT_TRUE(img[i] == 0.f || img[i] == 1.f) << "pixel " << i / 3 << ": " << img[i];
            seen_through[jitter] += img[i] == 1.f;
        }
    }
    std::printf(
        "[stratified] pixels whose ray hit the disk at their centre: jitter=false %d/64, "
        "jitter=true %d/64\n",
        seen_through[0], seen_through[1]);
    EXPECT_EQ(seen_through[0], 64);  // every ray through its pixel's centre
    // Control: a jittered ray hits its disk with probability pi / 100 (2 of 64 expected).
    EXPECT_LT(seen_through[1], 10);
}

TEST(SamplerStratified, Mitsuba06SceneWithSampleCountAndDimension) {
    // Mitsuba 0.6's stratified takes sampleCount and dimension (the number of stratified
    // dimensions before it falls back to independent numbers); femto stratifies them all and
    // accepts dimension with a note, not a warning.
    const std::string xml =
        "<scene version=\"0.6.0\"><sensor type=\"perspective\"><film type=\"hdrfilm\"><integer "
        "name=\"width\" value=\"4\"/><integer name=\"height\" value=\"4\"/></film><sampler "
        "type=\"stratified\"><integer name=\"sampleCount\" value=\"9\"/><integer "
        "name=\"dimension\" value=\"8\"/></sampler></sensor><shape type=\"rectangle\"/>"
        "</scene>";
    const int before = femto::warning_count();
    ::testing::internal::CaptureStderr();
    auto scene = femto::load_scene_string(xml);
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(femto::warning_count(), before);
    EXPECT_NE(err.find("note:"), std::string::npos) << err;
    EXPECT_NE(err.find("dimension=8"), std::string::npos) << err;
    const Sampler& s = scene->sensor().sampler();
    EXPECT_EQ(s.type_name(), "stratified");
    EXPECT_EQ(s.sample_count(), 9u);

    // A bad dimension is a located error; so is a misspelt parameter.
    std::string bad = xml;
    bad.replace(bad.find("value=\"8\""), 9, "value=\"0\"");
    EXPECT_THROW(femto::load_scene_string(bad), femto::SceneError);
    std::string misspelt = xml;
    misspelt.replace(misspelt.find("dimension"), 9, "dimensoin");
    EXPECT_THROW(femto::load_scene_string(misspelt), femto::SceneError);
}

// -- dimensions -------------------------------------------------------------------------------

// An integrator whose number of draws varies from sample to sample (BDPT) starts a decision at
// a fixed dimension with advance_to(): the pixel's samples then stratify that decision whatever
// was drawn before it. Without it (the control) the same draw lands on a different dimension in
// each sample and is not stratified.
TEST(SamplerDimensions, AdvanceToStratifiesADecisionAfterVaryingDraws) {
    constexpr uint32_t kSide = 8, kCount = kSide * kSide;  // 2^6 samples
    for (const char* type : {"ldsampler", "stratified"}) {
        SCOPED_TRACE(type);
        auto s = make_sampler(type, kCount);
        std::vector<Vec2> aligned, drifting;
        for (uint32_t i = 0; i < kCount; ++i) {
            for (bool align : {true, false}) {
                s->start(7, 3, i);
                EXPECT_EQ(s->dimension(), 0u);
                const uint32_t before = (i * 7) % 5;  // 0 to 4 draws
                for (uint32_t k = 0; k < before; ++k) s->next_1d();
                EXPECT_EQ(s->dimension(), before);
                if (align) {
                    s->advance_to(6);
                    EXPECT_EQ(s->dimension(), 6u);
                    aligned.push_back(s->next_2d());
                } else {
                    drifting.push_back(s->next_2d());
                }
                EXPECT_EQ(s->dimension(), (align ? 6u : before) + 1);
                // Never back: a dimension is drawn at most once in a sample.
                s->advance_to(1);
                EXPECT_EQ(s->dimension(), (align ? 6u : before) + 1);
            }
        }
        if (std::string(type) == "ldsampler") {
            EXPECT_TRUE(is_02_net(aligned, 6));
            EXPECT_FALSE(is_02_net(drifting, 6));
        } else {
            EXPECT_TRUE(one_per_cell(aligned, kSide));
            EXPECT_FALSE(one_per_cell(drifting, kSide));
        }
    }
}

// ldsampler's numbers are a function of (seed, pixel, sample, dimension): advancing to a
// dimension gives what drawing up to it would have.
TEST(SamplerDimensions, LdsamplerAdvanceEqualsDrawingThrough) {
    auto s = make_sampler("ldsampler", 16);
    for (uint32_t i = 0; i < 16; ++i) {
        s->start(5, 9, i);
        for (int k = 0; k < 4; ++k) s->next_2d();
        const Vec2 drawn = s->next_2d();
        s->start(5, 9, i);
        s->advance_to(4);
        const Vec2 advanced = s->next_2d();
        EXPECT_EQ(advanced.x, drawn.x);
        EXPECT_EQ(advanced.y, drawn.y);
    }
}

// Independent numbers need no alignment: the default advance_to() leaves them as they are.
TEST(SamplerDimensions, IndependentIgnoresAdvance) {
    auto s = make_sampler("independent", 16);
    s->start(5, 9, 2);
    const float a = s->next_1d(), b = s->next_1d();
    s->start(5, 9, 2);
    s->advance_to(100);
    EXPECT_EQ(s->next_1d(), a);
    EXPECT_EQ(s->next_1d(), b);
}

}  // namespace
