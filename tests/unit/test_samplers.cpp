// Tests of the sampler plugins (independent, ldsampler): parameters, determinism, range,
// uniformity (chi-square), the (0,2)-net stratification of ldsampler and its integration
// error against independent sampling.
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
#include "femto/sampler.h"

namespace {

using femto::PluginKind;
using femto::Properties;
using femto::Sampler;
using femto::Vec2;

const char* const kSamplerTypes[] = {"independent", "ldsampler"};

std::shared_ptr<Sampler> make_sampler(const std::string& type, int64_t sample_count,
                                      int64_t seed = 0, bool set_seed = false) {
    Properties props(type, {});
    props.set_int("sample_count", sample_count);
    if (set_seed) props.set_int("seed", seed);
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
constexpr int kChi2Tests = 2 /*samplers*/ * 4 /*cases*/;
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
        EXPECT_EQ(names, (std::set<std::string>{"sample_count", "seed"}));
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

TEST(SamplerLd, IndependentSamplerIsNotANet) {
    // Control for the test above: 64 random points almost never form a (0,6,2)-net.
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

}  // namespace
