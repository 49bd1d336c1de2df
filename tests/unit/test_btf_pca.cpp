// PCA compression of a BTF (btf/pca.h): the rank-3 BTF A is reconstructed to float rounding with
// k = 3 from any format, and for k < 3 the error is the one the exact singular values predict
// (Eckart-Young); the hierarchy built on PCA factors of a BDI matches the closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "btf/pca.h"
#include "btf/synth.h"
#include "btf_test_util.h"
#include "femto/btf_prefilter.h"
#include "femto/testing/render.h"

namespace {

using namespace femto;
using namespace femto::btf;
constexpr double kPiD = 3.14159265358979323846;

synth::Options btf_a(Format format) { return femto::test::small_btf_a(format); }

std::shared_ptr<const Data> written(const synth::Options& o, const std::string& name) {
    return read(femto::test::write_btf(o, "btf-pca", name));
}

/// ||M - angular spatial^T||_F / ||M||_F for channel c, measured value by value.
double reconstruction_error(const Data& data, const Factors& f, int c) {
    const Header& h = data.header();
    const size_t nl = h.lights.size(), k = f.components;
    double err = 0, norm = 0;
    for (uint32_t y = 0; y < h.height; ++y)
        for (uint32_t x = 0; x < h.width; ++x)
            for (size_t v = 0; v < h.views.size(); ++v)
                for (size_t l = 0; l < nl; ++l) {
                    const double m = data.value(x, y, uint32_t(l), uint32_t(v))[c];
                    double approx = 0;
                    for (size_t i = 0; i < k; ++i)
                        approx += double(f.angular[c][(l + nl * v) * k + i]) *
                                  f.spatial[c][(x + size_t(h.width) * y) * k + i];
                    err += (m - approx) * (m - approx);
                    norm += m * m;
                }
    return std::sqrt(err / norm);
}

/// The exact singular values of channel c's matrix, from its (texels x texels) Gram matrix.
std::vector<double> exact_singular_values(const Data& data, int c) {
    const Header& h = data.header();
    const size_t texels = size_t(h.width) * h.height;
    std::vector<std::vector<double>> cols(texels);
    for (uint32_t y = 0; y < h.height; ++y)
        for (uint32_t x = 0; x < h.width; ++x)
            for (size_t v = 0; v < h.views.size(); ++v)
                for (size_t l = 0; l < h.lights.size(); ++l)
                    cols[x + size_t(h.width) * y].push_back(
                        data.value(x, y, uint32_t(l), uint32_t(v))[c]);
    std::vector<double> gram(texels * texels), values, vectors;
    for (size_t i = 0; i < texels; ++i)
        for (size_t j = 0; j < texels; ++j)
            for (size_t a = 0; a < cols[i].size(); ++a)
                gram[i * texels + j] += cols[i][a] * cols[j][a];
    symmetric_eigen(gram, texels, values, vectors);
    for (double& v : values) v = std::sqrt(std::max(0.0, v));
    return values;
}

TEST(BtfPca, RankThreeReconstructsToFloatRoundingAndFewerFollowEckartYoung) {
    const auto data = written(btf_a(Format::Dfmf), "a.dfmf");
    for (int c = 0; c < 3; ++c) {
        const std::vector<double> sigma = exact_singular_values(*data, c);
        double total = 0;
        for (double s : sigma) total += s * s;
        EXPECT_LT(sigma[3], 1e-5 * sigma[0]) << "BTF A has rank 3 per channel";
        for (uint32_t k : {1u, 2u, 3u}) {
            PcaSettings settings;
            settings.components = k;
            PcaReport report;
            const Factors f = factorize(*data, settings, &report);
            double rest = 0;
            for (size_t i = k; i < sigma.size(); ++i) rest += sigma[i] * sigma[i];
            const double predicted = std::sqrt(rest / total);
            const double measured = reconstruction_error(*data, f, c);
            if (k == 3) {
                EXPECT_LT(measured, 2e-6);  // float factors
            } else {
                // A rank-3 matrix is captured exactly by the range finder (k + 8 directions):
                // the error is the Eckart-Young optimum, to float rounding.
                EXPECT_NEAR(measured, predicted, 1e-5 + 1e-4 * predicted) << "k = " << k;
                EXPECT_GT(measured, 1e-3);
            }
            std::printf("[pca] channel %d, k = %u: error %.6g (Eckart-Young %.6g), energy %.8f\n",
                        c, k, measured, predicted, report.energy_kept[c]);
            EXPECT_NEAR(report.relative_error[c], predicted, 1e-5 + 1e-4 * predicted);
            EXPECT_NEAR(report.energy_kept[c], 1 - predicted * predicted, 1e-6);
        }
    }
}

TEST(BtfPca, BdiAndLogYuvFilesGetTheirFactorsToo) {
    PcaSettings settings;
    settings.components = 3;
    auto logyuv = btf_a(Format::Dfmf);
    logyuv.color_model = kColorLogYuv;
    const auto log_data = written(logyuv, "log.dfmf");
    const auto bdi = written(btf_a(Format::Bdi), "a.bdi");
    for (int c = 0; c < 3; ++c) {
        // Decoded log-YUV values are BTF A again (rank 3) to float rounding.
        EXPECT_LT(reconstruction_error(*log_data, factorize(*log_data, settings), c), 5e-6);
        // Half floats add noise of 2^-11 relative: rank 3 leaves about that much.
        const double e3 = reconstruction_error(*bdi, factorize(*bdi, settings), c);
        EXPECT_LT(e3, 3e-4);
        settings.components = 8;
        EXPECT_LT(reconstruction_error(*bdi, factorize(*bdi, settings), c), e3);
        settings.components = 3;
    }
}

TEST(BtfPca, HierarchyOnPcaFactorsOfABdiMatchesTheClosedForm) {
    const synth::Options o = btf_a(Format::Bdi);
    const auto data = written(o, "h.bdi");
    PcaSettings settings;
    settings.components = 3;
    const Hierarchy h(factorize(*data, settings), o.directions, o.directions, PrefilterSettings{});
    const synth::HarmonicBtf closed(o.width, o.height);
    double worst = 0;
    for (int level = 0; level < h.levels(); ++level) {
        const uint32_t bx = o.width / h.width(level), by = o.height / h.height(level);
        for (uint32_t l = 0; l < 81; l += 10)
            for (uint32_t v = 0; v < 81; v += 13) {
                const Color got = h.value(level, 0, 0, 2, 3, l, v);
                for (int c = 0; c < 3; ++c) {
                    double want = 0;
                    for (int k = 0; k < 3; ++k)
                        want += closed.spatial_box_mean(c, k, 0, 0, bx, by) *
                                synth::HarmonicBtf::angular_cap_mean(
                                    k, o.directions[l], o.directions[v], 30 * kPiD / 180,
                                    45 * kPiD / 180);
                    worst = std::max(worst, std::abs(got[c] - want));
                }
            }
    }
    // The BDI's half rounding (2^-11 of values <= 1) averages down under the filters.
    EXPECT_LT(worst, 5e-4);
}

}  // namespace
