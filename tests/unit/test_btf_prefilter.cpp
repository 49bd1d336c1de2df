// The prefiltered BTF hierarchy (btf/prefilter.h, btf/angular_filter.h): every (level, light
// cone, view cone) entry of the synthetic BTF A matches its closed form (box means over texel
// blocks, Funk-Hecke scalings over cones), the angular filter's pieces are exact on their own,
// and the factors read from each format give the same hierarchy.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "btf/angular_filter.h"
#include "btf/pca.h"
#include "btf/synth.h"
#include "btf_test_util.h"
#include "femto/btf_prefilter.h"
#include "femto/testing/render.h"

namespace {

using namespace femto;
using namespace femto::btf;

TEST(BtfPrefilter, BoxBandScalesAreFunkHecke) {
    for (double deg : {5.0, 15.0, 30.0, 45.0}) {
        const double a = deg * kPiD / 180, c = std::cos(a);
        const std::vector<double> s = kernel_band_scales(FilterKernel::Box, a, 3);
        EXPECT_NEAR(s[0], 1.0, 1e-12);
        EXPECT_NEAR(s[1], (1 + c) / 2, 1e-12);
        EXPECT_NEAR(s[2], c * (1 + c) / 2, 1e-12);
    }
    const std::vector<double> none = kernel_band_scales(FilterKernel::Gaussian, 0.0, 4);
    for (double v : none) EXPECT_EQ(v, 1.0);
}

TEST(BtfPrefilter, SmoothKernelScalesMatchDirectQuadrature) {
    // An independent midpoint rule (10^5 steps) of k(theta) P_l(cos theta) sin theta over the
    // cone, with pbrt's Gaussian (alpha 2) and Lanczos (tau 3) shapes over theta / cone angle.
    const double a = 30 * kPiD / 180;
    auto gaussian = [&](double t) { return std::exp(-2 * (t / a) * (t / a)) - std::exp(-2.0); };
    auto sinc = [](double x) { return x < 1e-9 ? 1.0 : std::sin(kPiD * x) / (kPiD * x); };
    auto lanczos = [&](double t) { return sinc(3 * t / a) * sinc(t / a); };
    auto p2 = [](double x) { return 0.5 * (3 * x * x - 1); };
    for (const auto& [kernel, k] :
         {std::pair{FilterKernel::Gaussian, std::function<double(double)>(gaussian)},
          std::pair{FilterKernel::Lanczos, std::function<double(double)>(lanczos)}}) {
        double s1 = 0, s2 = 0, total = 0;
        constexpr int n = 100000;
        for (int i = 0; i < n; ++i) {
            const double t = a * (i + 0.5) / n, w = k(t) * std::sin(t);
            total += w, s1 += w * std::cos(t), s2 += w * p2(std::cos(t));
        }
        const std::vector<double> s = kernel_band_scales(kernel, a, 2);
        EXPECT_NEAR(s[1], s1 / total, 1e-7);
        EXPECT_NEAR(s[2], s2 / total, 1e-7);
        if (kernel == FilterKernel::Gaussian) {
            EXPECT_LT(s[2], s[1]);  // (Lanczos has negative lobes: its scales can exceed 1)
        }
    }
}

TEST(BtfPrefilter, SphericalHarmonicsAreOrthonormal) {
    constexpr int degree = 4, count = 25, nt = 300, np = 600;
    std::vector<double> gram(count * count, 0.0), y(count);
    for (int i = 0; i < nt; ++i)
        for (int j = 0; j < np; ++j) {
            const double t = kPiD * (i + 0.5) / nt, p = 2 * kPiD * (j + 0.5) / np;
            const double w = std::sin(t) * (kPiD / nt) * (2 * kPiD / np);
            sh_eval(degree,
                    Vec3(float(std::sin(t) * std::cos(p)), float(std::sin(t) * std::sin(p)),
                         float(std::cos(t))),
                    y.data());
            for (int a = 0; a < count; ++a)
                for (int b = 0; b < count; ++b) gram[a * count + b] += w * y[a] * y[b];
        }
    // The midpoint rule's error on these smooth integrands is ~1e-5 at this resolution.
    for (int a = 0; a < count; ++a)
        for (int b = 0; b < count; ++b) EXPECT_NEAR(gram[a * count + b], a == b ? 1.0 : 0.0, 2e-4);
}

TEST(BtfPrefilter, AngularFilterIsIdentityAtZeroAndScalesBands) {
    const std::vector<Vec3> dirs = ubo2014_directions();
    const AngularFilter filter(dirs, 2);
    const std::vector<double> identity = filter.matrix(FilterKernel::Box, 0.0);
    for (size_t i = 0; i < dirs.size(); ++i)
        for (size_t j = 0; j < dirs.size(); ++j)
            EXPECT_NEAR(identity[i * dirs.size() + j], i == j ? 1.0 : 0.0, 1e-12);
    const Vec3 axis = normalize(Vec3(0.3f, -0.4f, 0.8f));
    const double a = 30 * kPiD / 180, c = std::cos(a);
    const std::vector<double> f = filter.matrix(FilterKernel::Box, a);
    double worst = 0;
    for (size_t i = 0; i < dirs.size(); ++i) {
        double band1 = 0, band2 = 0;
        for (size_t j = 0; j < dirs.size(); ++j) {
            const double x = dot(dirs[j], axis);
            band1 += f[i * dirs.size() + j] * x;
            band2 += f[i * dirs.size() + j] * 0.5 * (3 * x * x - 1);
        }
        const double x = dot(dirs[i], axis);
        worst = std::max(worst, std::abs(band1 - (1 + c) / 2 * x));
        worst = std::max(worst, std::abs(band2 - c * (1 + c) / 2 * 0.5 * (3 * x * x - 1)));
    }
    EXPECT_LT(worst, 1e-6);
}

TEST(BtfPrefilter, AngularFilterKeepsConstantsAndSpreadsHighlights) {
    // A constant (band 0) stays; a highlight at one sample (all bands, mostly the residual the
    // fit leaves to the cone quadrature) spreads to its neighbours, more for wider cones.
    const std::vector<Vec3> dirs = ubo2003_directions();
    const AngularFilter filter(dirs, 2);
    const size_t n = dirs.size(), peak = 20;
    double previous_peak = 1.0;
    for (double deg : {15.0, 30.0, 45.0})
        for (FilterKernel kernel :
             {FilterKernel::Box, FilterKernel::Gaussian, FilterKernel::Lanczos}) {
            const std::vector<double> f = filter.matrix(kernel, deg * kPiD / 180);
            for (size_t i = 0; i < n; ++i) {
                double row = 0;
                for (size_t j = 0; j < n; ++j) row += f[i * n + j];
                EXPECT_NEAR(row, 1.0, 1e-8);
            }
            if (kernel == FilterKernel::Box) {
                EXPECT_LT(f[peak * n + peak], previous_peak);
                previous_peak = f[peak * n + peak];
            }
        }
    EXPECT_LT(previous_peak, 0.5);
}

synth::Options btf_a(Format format) { return femto::test::small_btf_a(format); }

Factors factors_of(const synth::Options& o, const std::string& name) {
    const std::string path = femto::test::write_btf(o, "btf-prefilter", name);
    Factors f;
    EXPECT_TRUE(linear_factors(*read(path), f));
    return f;
}

TEST(BtfPrefilter, EveryEntryOfBtfAMatchesItsClosedForm) {
    const synth::Options o = btf_a(Format::Dfmf);
    const Hierarchy h(factors_of(o, "a.dfmf"), o.directions, o.directions, PrefilterSettings{});
    ASSERT_EQ(h.levels(), 4);  // 8 x 4, 4 x 2, 2 x 1, 1 x 1
    const synth::HarmonicBtf closed(o.width, o.height);
    const double cones[] = {0, 15, 30, 45};
    double worst = 0;
    for (int level = 0; level < h.levels(); ++level) {
        const uint32_t bx = o.width / h.width(level), by = o.height / h.height(level);
        for (uint32_t y = 0; y < h.height(level); ++y)
            for (uint32_t x = 0; x < h.width(level); ++x)
                for (size_t i = 0; i < 4; ++i)
                    for (size_t j = 0; j < 4; ++j)
                        for (uint32_t l = 0; l < 81; l += 7)
                            for (uint32_t v = 0; v < 81; v += 5) {
                                const Color got = h.value(level, x, y, i, j, l, v);
                                for (int c = 0; c < 3; ++c) {
                                    double want = 0;
                                    for (int k = 0; k < 3; ++k)
                                        want +=
                                            closed.spatial_box_mean(c, k, x * bx, y * by, bx, by) *
                                            synth::HarmonicBtf::angular_cap_mean(
                                                k, o.directions[l], o.directions[v],
                                                cones[i] * kPiD / 180, cones[j] * kPiD / 180);
                                    worst = std::max(worst, std::abs(got[c] - want));
                                }
                            }
    }
    // Float factors and a float sum of three terms of magnitude <= 0.6: a few 1e-7; the
    // angular fit's regularization (1e-9) moves band-2 terms by ~1e-8.
    EXPECT_LT(worst, 2e-6);
    std::printf("[prefilter] worst |entry - closed form| over all levels and cones: %.2g\n", worst);
}

TEST(BtfPrefilter, FormatsAndCosineFlagGiveTheSameHierarchy) {
    const synth::Options dfmf = btf_a(Format::Dfmf);
    synth::Options fmf = btf_a(Format::Fmf), flagged = btf_a(Format::Dfmf);
    flagged.cosine_flag = true;
    const PrefilterSettings settings;
    const Hierarchy a(factors_of(dfmf, "s.dfmf"), dfmf.directions, dfmf.directions, settings);
    const Hierarchy b(factors_of(fmf, "s.fmf"), fmf.directions, fmf.directions, settings);
    const Hierarchy c(factors_of(flagged, "s-cos.dfmf"), flagged.directions, flagged.directions,
                      settings);
    for (int level : {0, 2})
        for (uint32_t l : {3u, 40u}) {
            const Color va = a.value(level, 1, 0, 2, 1, l, 77),
                        vb = b.value(level, 1, 0, 2, 1, l, 77),
                        vc = c.value(level, 1, 0, 2, 1, l, 77);
            for (int ch = 0; ch < 3; ++ch) {
                EXPECT_NEAR(va[ch], vb[ch], 2e-6f);
                EXPECT_NEAR(va[ch], vc[ch], 2e-6f);
            }
        }
    // BDI has no factors: it needs a factorization of its values first.
    Factors none;
    const std::string bdi = (femto::testing::temp_dir("btf-prefilter") / "a.bdi").string();
    synth::write(bdi, btf_a(Format::Bdi));
    EXPECT_FALSE(linear_factors(*read(bdi), none));
}

}  // namespace

namespace {

DirectionMesh::Weights at_sample(uint32_t i) {
    DirectionMesh::Weights w;
    w.index[0] = i;
    w.weight[0] = 1.f;
    return w;
}

TEST(BtfPrefilter, LookupSelectsAndBlendsLevelsAndCones) {
    const synth::Options o = btf_a(Format::Dfmf);
    const Hierarchy h(factors_of(o, "lookup.dfmf"), o.directions, o.directions,
                      PrefilterSettings{});
    const double deg = kPiD / 180;
    // Texel (1, 0) of level 1 (4 x 2): its centre in uv (row 0 is the top).
    const Vec2 uv1 = {1.5f / 4, 1.f - 0.5f / 2};
    const auto l = at_sample(12), v = at_sample(57);
    auto near = [](const Color& a, const Color& b, float tol) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], tol);
    };
    near(h.lookup(uv1, 2.0, 30 * deg, 15 * deg, l, v), h.value(1, 1, 0, 2, 1, 12, 57), 1e-6f);
    // Halfway between cones 15 and 30 (light) and between 30 and 45 (view).
    const Color mid = h.lookup(uv1, 2.0, 22.5 * deg, 37.5 * deg, l, v);
    Color want(0.f);
    for (size_t i : {1u, 2u})
        for (size_t j : {2u, 3u}) want += h.value(1, 1, 0, i, j, 12, 57) * 0.25f;
    near(mid, want, 1e-6f);
    // Between levels 1 and 2 (ratio 2^1.5): at a point that is a texel centre of neither,
    // the blend of the two levels' bilinear lookups.
    const Vec2 uv = {0.3f, 0.8f};
    const Color a = h.lookup(uv, 2.0, 0, 0, l, v), b = h.lookup(uv, 4.0, 0, 0, l, v);
    near(h.lookup(uv, std::pow(2.0, 1.5), 0, 0, l, v), (a + b) * 0.5f, 1e-6f);
    // Below one texel per pixel: the finest level; beyond the coarsest: the coarsest.
    near(h.lookup(uv, 0.25, 0, 0, l, v), h.lookup(uv, 1.0, 0, 0, l, v), 0.f);
    near(h.lookup(uv, 1e6, 0, 0, l, v), h.value(3, 0, 0, 0, 0, 12, 57), 1e-6f);
    // Cones beyond the last angle clamp to it.
    near(h.lookup(uv1, 2.0, 80 * deg, 60 * deg, l, v), h.value(1, 1, 0, 3, 3, 12, 57), 1e-6f);
}

// lookup_box() is the mean of a level's bilinear texture over the rectangle: against a 2D
// midpoint rule of 400 x 400 bilinear lookups (h.lookup at ratio 0 is level 0's bilinear
// texture), for rectangles that straddle texel centres, wrap around the texture's edges, are
// thinner than a texel, and (on level 1) are too wide for level 0.
TEST(BtfPrefilter, BoxLookupIsTheMeanOverTheRectangle) {
    synth::Options o = btf_a(Format::Dfmf);
    o.width = 16;
    o.height = 8;
    const Hierarchy h(factors_of(o, "box.dfmf"), o.directions, o.directions, PrefilterSettings{});
    const auto l = at_sample(12), v = at_sample(57);
    struct Case {
        Vec2 uv, extent;  // extent in level-0 texels
        int level;        // the level lookup_box should take
    };
    for (const Case& t :
         {Case{{0.31f, 0.62f}, {3.3f, 2.7f}, 0}, Case{{0.01f, 0.97f}, {4.f, 1.5f}, 0},
          Case{{0.5f, 0.5f}, {0.2f, 7.9f}, 0}, Case{{0.77f, 0.2f}, {11.2f, 5.f}, 1}}) {
        const int n = 400;
        const double scale = std::ldexp(1.0, t.level);  // level texels per level-0 texel: 1/scale
        Color sum(0.f);
        double sr = 0, sg = 0, sb = 0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const double du = (i + 0.5) / n - 0.5, dv = (j + 0.5) / n - 0.5;
                const Vec2 uv(float(t.uv.x + du * t.extent.x / o.width),
                              float(t.uv.y + dv * t.extent.y / o.height));
                // Level `level`'s bilinear texture: lookup at a ratio that selects it alone.
                const Color c = h.lookup(uv, scale, 0, 0, l, v);
                sr += c.r;
                sg += c.g;
                sb += c.b;
            }
        sum = Color(float(sr / (n * n)), float(sg / (n * n)), float(sb / (n * n)));
        const Color box = h.lookup_box(t.uv, t.extent, 0, 0, l, v);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(box[c], sum[c], 2e-4 * std::abs(sum[c]) + 1e-6)
                << "uv (" << t.uv.x << ", " << t.uv.y << "), extent (" << t.extent.x << ", "
                << t.extent.y << "), channel " << c;
    }
    // A point (zero extent) is the bilinear lookup.
    const Color point = h.lookup_box({0.4f, 0.3f}, {0.f, 0.f}, 0, 0, l, v);
    const Color bilinear = h.lookup({0.4f, 0.3f}, 0, 0, 0, l, v);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(point[c], bilinear[c], 1e-6f);
}

TEST(BtfPrefilter, BadSettingsAreRefused) {
    const synth::Options o = btf_a(Format::Dfmf);
    const Factors f = factors_of(o, "bad.dfmf");
    PrefilterSettings s;
    s.cone_angles_deg = {5, 15};
    EXPECT_THROW(Hierarchy(f, o.directions, o.directions, s), std::invalid_argument);
    s.cone_angles_deg = {0, 30, 15};
    EXPECT_THROW(Hierarchy(f, o.directions, o.directions, s), std::invalid_argument);
    s.cone_angles_deg = {0, 15};
    EXPECT_THROW(Hierarchy(f, o.directions, ubo2014_directions(), s), std::invalid_argument);
}

}  // namespace

namespace {

TEST(BtfPrefilter, CacheIsWrittenReusedAndKeyedByFileAndSettings) {
    const auto dir = femto::testing::temp_dir("btf-cache");
    const std::string file = (dir / "c.dfmf").string();
    synth::Options o = btf_a(Format::Dfmf);
    synth::write(file, o);
    const PcaSettings pca;
    PrefilterSettings settings;
    PrefilterReport first, second, other, changed, corrupt;
    const auto h1 = prefiltered(file, *read(file), settings, pca, true, first);
    EXPECT_FALSE(first.from_cache);
    ASSERT_TRUE(std::filesystem::exists(first.cache_file)) << first.cache_problem;
    const auto h2 = prefiltered(file, *read(file), settings, pca, true, second);
    EXPECT_TRUE(second.from_cache);
    EXPECT_EQ(second.cache_file, first.cache_file);
    const auto l = at_sample(30), v = at_sample(7);
    for (double ratio : {1.0, 3.0, 8.0}) {
        const Color a = h1->lookup({0.3f, 0.4f}, ratio, 0.2, 0.5, l, v);
        const Color b = h2->lookup({0.3f, 0.4f}, ratio, 0.2, 0.5, l, v);
        EXPECT_TRUE(a == b);
    }
    // Other settings: another cache file.
    settings.cone_angles_deg = {0, 20, 40};
    prefiltered(file, *read(file), settings, pca, true, other);
    EXPECT_FALSE(other.from_cache);
    EXPECT_NE(other.cache_file, first.cache_file);
    // Another file under the same name: its CRC differs, the old cache is not used.
    settings = PrefilterSettings{};
    o.cosine_flag = true;
    synth::write(file, o);
    prefiltered(file, *read(file), settings, pca, true, changed);
    EXPECT_FALSE(changed.from_cache);
    // A truncated cache file is rebuilt, not trusted.
    const auto size = std::filesystem::file_size(changed.cache_file);
    std::filesystem::resize_file(changed.cache_file, size / 2);
    prefiltered(file, *read(file), settings, pca, true, corrupt);
    EXPECT_FALSE(corrupt.from_cache);
    EXPECT_EQ(std::filesystem::file_size(corrupt.cache_file), size);
}

TEST(BtfPrefilter, AnUnwritableCacheIsReportedNotFatal) {
    const auto dir = femto::testing::temp_dir("btf-cache-blocked");
    const std::string file = (dir / "b.dfmf").string();
    synth::write(file, btf_a(Format::Dfmf));
    PrefilterReport probe;
    prefiltered(file, *read(file), PrefilterSettings{}, PcaSettings{}, false, probe);
    EXPECT_TRUE(probe.cache_file.empty());
    // Find the cache's name, then put a directory in its way.
    PrefilterReport named;
    prefiltered(file, *read(file), PrefilterSettings{}, PcaSettings{}, true, named);
    const std::string blocked = named.cache_file;
    std::filesystem::remove(blocked);
    std::filesystem::create_directories(std::filesystem::path(blocked) / "x");
    PrefilterReport report;
    const auto h = prefiltered(file, *read(file), PrefilterSettings{}, PcaSettings{}, true, report);
    ASSERT_TRUE(h);
    EXPECT_FALSE(report.from_cache);
    EXPECT_FALSE(report.cache_problem.empty());
    EXPECT_FALSE(std::filesystem::exists(blocked + ".tmp"));
}

}  // namespace

namespace {

TEST(BtfPrefilter, LevelSpectrumIsTheLevelsSingularValues) {
    // Compare with the singular values of the level's explicit matrix (texels x texels Gram).
    const synth::Options o = btf_a(Format::Dfmf);
    const Hierarchy h(factors_of(o, "spectrum.dfmf"), o.directions, o.directions,
                      PrefilterSettings{});
    for (int level : {0, 1, 3}) {
        const size_t texels = size_t(h.width(level)) * h.height(level);
        std::vector<double> gram(texels * texels, 0.0), values, vectors;
        for (size_t i = 0; i < texels; ++i)
            for (size_t j = 0; j < texels; ++j)
                for (uint32_t v = 0; v < 81; ++v)
                    for (uint32_t l = 0; l < 81; ++l) {
                        const uint32_t w = h.width(level);
                        gram[i * texels + j] +=
                            double(h.value(level, uint32_t(i % w), uint32_t(i / w), 0, 0, l, v).g) *
                            h.value(level, uint32_t(j % w), uint32_t(j / w), 0, 0, l, v).g;
                    }
        symmetric_eigen(gram, texels, values, vectors);
        const std::vector<double> spectrum = h.level_spectrum(level, 1);
        for (size_t i = 0; i < std::min<size_t>(3, texels); ++i)
            EXPECT_NEAR(spectrum[i], std::sqrt(std::max(0.0, values[i])), 1e-4 * spectrum[0]);
    }
}

}  // namespace

namespace {

TEST(BtfPrefilter, GaussianAndLanczosEntriesMatchTheirClosedForms) {
    // The smooth kernels: spatially, each level scales BTF A's cosines by the downsampling
    // weights' frequency response; angularly, band l by the kernel's Funk-Hecke coefficient.
    // Both are exact for BTF A, so the tolerance is float rounding as for the box.
    const synth::Options o = btf_a(Format::Dfmf);
    const Factors base = factors_of(o, "smooth.dfmf");
    const synth::HarmonicBtf closed(o.width, o.height);
    for (FilterKernel kernel : {FilterKernel::Gaussian, FilterKernel::Lanczos}) {
        PrefilterSettings settings;
        settings.kernel = kernel;
        const Hierarchy h(base, o.directions, o.directions, settings);
        const std::array<float, 4> weights = downsampling_weights(kernel);
        double worst = 0;
        for (int level = 0; level < h.levels(); ++level)
            for (size_t i = 0; i < 4; ++i)
                for (size_t j = 0; j < 4; ++j) {
                    const auto sl =
                        kernel_band_scales(kernel, settings.cone_angles_deg[i] * kPiD / 180, 2);
                    const auto sv =
                        kernel_band_scales(kernel, settings.cone_angles_deg[j] * kPiD / 180, 2);
                    for (uint32_t y = 0; y < h.height(level); ++y)
                        for (uint32_t x = 0; x < h.width(level); ++x)
                            for (uint32_t l = 0; l < 81; l += 11)
                                for (uint32_t v = 0; v < 81; v += 9) {
                                    const Color got = h.value(level, x, y, i, j, l, v);
                                    for (int c = 0; c < 3; ++c) {
                                        double want = 0;
                                        for (int k = 0; k < 3; ++k)
                                            want +=
                                                closed.spatial_downsampled(c, k, level, x, y,
                                                                           weights) *
                                                synth::HarmonicBtf::angular_filtered(
                                                    k, o.directions[l], o.directions[v], sl, sv);
                                        worst = std::max(worst, std::abs(got[c] - want));
                                    }
                                }
                }
        EXPECT_LT(worst, 2e-6) << (kernel == FilterKernel::Gaussian ? "gaussian" : "lanczos");
        std::printf("[prefilter] %s: worst |entry - closed form| %.2g\n",
                    kernel == FilterKernel::Gaussian ? "gaussian" : "lanczos", worst);
    }
    // The box weights are the 2 x 2 mean, whose cascade is the Dirichlet box mean.
    const std::array<float, 4> box = downsampling_weights(FilterKernel::Box);
    EXPECT_NEAR(closed.spatial_downsampled(0, 1, 2, 1, 0, box),
                closed.spatial_box_mean(0, 1, 4, 0, 4, 4), 1e-12);
}

}  // namespace
