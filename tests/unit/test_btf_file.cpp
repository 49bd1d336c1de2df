// The Bonn BTF formats (femto/btf.h): every format written by the synthetic generator reads
// back the generator's values at the sampled directions, and corrupt files are located errors.
#include <Imath/half.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "btf/synth.h"
#include "btf/vgroove.h"
#include "btf_test_util.h"
#include "femto/btf.h"
#include "femto/error.h"
#include "femto/testing/render.h"

namespace {

using namespace femto;
namespace fs = std::filesystem;

btf::synth::Options small_options(btf::Format format) { return femto::test::small_btf_a(format); }

std::string write_synth(const btf::synth::Options& o, const std::string& name) {
    return femto::test::write_btf(o, "btf-file", name);
}

/// Checks every (x, y) and a spread of (l, v) pairs against the generator within `tolerance`
/// (absolute; values are ~0.05 .. 1).
void expect_values(const btf::Data& data, const btf::synth::Options& o, float tolerance) {
    const uint32_t n = uint32_t(o.directions.size());
    float worst = 0.f;
    for (uint32_t y = 0; y < o.height; ++y)
        for (uint32_t x = 0; x < o.width; ++x)
            for (uint32_t v = 0; v < n; v += 7)
                for (uint32_t l = 0; l < n; l += 3) {
                    const Color want = btf::synth::reference_value(o, x, y, l, v);
                    const Color got = data.value(x, y, l, v);
                    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(got[c] - want[c]));
                }
    EXPECT_LE(worst, tolerance);
}

TEST(BtfFile, BdiHoldsTheGeneratorsValuesAsHalfFloats) {
    const auto o = small_options(btf::Format::Bdi);
    const auto data = btf::read(write_synth(o, "a.bdi"));
    ASSERT_EQ(data->header().format, btf::Format::Bdi);
    EXPECT_EQ(data->header().width, 8u);
    EXPECT_EQ(data->header().height, 4u);
    // Exactly the half-float rounding of the generator's value (the file's storage type).
    for (uint32_t y = 0; y < 4; ++y)
        for (uint32_t x = 0; x < 8; ++x)
            for (uint32_t lv : {0u, 17u, 80u}) {
                const Color want = btf::synth::reference_value(o, x, y, lv, 80 - lv);
                const Color got = data->value(x, y, lv, 80 - lv);
                for (int c = 0; c < 3; ++c) EXPECT_EQ(got[c], float(Imath::half(want[c])));
            }
}

TEST(BtfFile, HeaderRoundTrips) {
    auto o = small_options(btf::Format::Dfmf);
    o.directions = btf::ubo2014_directions();
    o.width = 3;
    o.height = 5;
    const auto data = btf::read(write_synth(o, "header.dfmf"));
    const btf::Header& h = data->header();
    ASSERT_EQ(h.light_count(), 151u);
    ASSERT_EQ(h.view_count(), 151u);
    EXPECT_EQ(h.width, 3u);
    EXPECT_EQ(h.height, 5u);
    EXPECT_EQ(h.measurement_setup, "femto btf synth");
    EXPECT_FALSE(h.cosine_flag);
    for (size_t i = 0; i < 151; ++i) {
        // Angles are stored as 32-bit floats: 1e-6 covers their rounding.
        EXPECT_NEAR(h.lights[i].x, o.directions[i].x, 1e-6f);
        EXPECT_NEAR(h.lights[i].y, o.directions[i].y, 1e-6f);
        EXPECT_NEAR(h.views[i].z, o.directions[i].z, 1e-6f);
    }
    EXPECT_EQ(data->components(), 3u);
}

TEST(BtfFile, DfmfRank3ReconstructsToFloatRounding) {
    const auto o = small_options(btf::Format::Dfmf);
    const auto data = btf::read(write_synth(o, "rank3.dfmf"));
    EXPECT_EQ(data->components(), 3u);
    // Three float products of magnitude <= 0.6: a few float ulps of 1.
    expect_values(*data, o, 1e-6f);
}

TEST(BtfFile, DfmfHalfMatricesStayWithinHalfRounding) {
    auto o = small_options(btf::Format::Dfmf);
    o.half = true;
    const auto data = btf::read(write_synth(o, "half.dfmf"));
    // Each factor rounds by <= 2^-11 relative; three terms of |T G| <= 0.65 in total.
    expect_values(*data, o, 2.f * 0.65f * 0.000489f + 1e-6f);
}

TEST(BtfFile, DfmfLogYuvColourModelDecodes) {
    auto o = small_options(btf::Format::Dfmf);
    o.color_model = btf::kColorLogYuv;
    const auto data = btf::read(write_synth(o, "logyuv.dfmf"));
    EXPECT_EQ(data->header().color_model, btf::kColorLogYuv);
    // exp/log and the YUV matrices in float: ~1e-6 relative, on values <= 1.
    expect_values(*data, o, 3e-6f);
}

TEST(BtfFile, FmfDecodes) {
    const auto o = small_options(btf::Format::Fmf);
    const auto data = btf::read(write_synth(o, "a.fmf"));
    EXPECT_EQ(data->header().format, btf::Format::Fmf);
    EXPECT_EQ(data->components(), 9u);
    expect_values(*data, o, 1e-6f);
}

TEST(BtfFile, CosineFlagIsDividedOut) {
    for (const btf::Format format : {btf::Format::Bdi, btf::Format::Dfmf, btf::Format::Fmf}) {
        auto o = small_options(format);
        o.cosine_flag = true;
        const auto data = btf::read(write_synth(o, std::string("cos.") + btf::format_name(format)));
        EXPECT_TRUE(data->header().cosine_flag);
        // BDI: half rounding of B cos, divided by cos >= cos 75 deg: 2^-11 relative of <= 1.
        expect_values(*data, o, format == btf::Format::Bdi ? 5e-4f : 2e-6f);
    }
}

TEST(BtfFile, VGrooveTexelsAverageToTheClosedForm) {
    // BTF B: every texel holds the exact mean of the groove over its column, so the mean of a
    // row of texels (the coarsest filtered level) is the V-cavity's period average.
    for (const btf::Format format : {btf::Format::Bdi, btf::Format::Dfmf}) {
        auto o = small_options(format);
        o.kind = btf::synth::Kind::VGroove;
        o.width = 16;
        o.height = 2;
        const auto data = btf::read(write_synth(o, std::string("vg.") + btf::format_name(format)));
        const btf::VGroove groove{o.vgroove_slope_deg * kPi / 180, 1.0};
        double worst = 0;
        for (uint32_t l = 0; l < 81; l += 4)
            for (uint32_t v = 0; v < 81; v += 5) {
                const double want =
                    btf::vgroove_period_average(groove, o.directions[l], o.directions[v]);
                for (int c = 0; c < 3; ++c) {
                    double mean = 0;
                    for (uint32_t x = 0; x < o.width; ++x) mean += data->value(x, 1, l, v)[c];
                    mean /= o.width;
                    worst = std::max(worst, std::abs(mean - want * o.vgroove_albedo[c]) /
                                                (want * o.vgroove_albedo[c] + 1e-3));
                }
            }
        // BDI: half floats, 2^-11 relative; DFMF: float factors, ~1e-7.
        EXPECT_LE(worst, format == btf::Format::Bdi ? 5e-4 : 1e-6) << btf::format_name(format);
    }
}

// ---- bad input -------------------------------------------------------------------------------

std::string file_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string write_bytes(const std::string& bytes, const std::string& name) {
    const std::string path = (femto::testing::temp_dir("btf-bad") / name).string();
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return path;
}

/// Reading `bytes` fails with a SceneError naming the file and containing `field`.
void expect_bad(const std::string& bytes, const std::string& field) {
    const std::string path = write_bytes(bytes, "bad.btf");
    try {
        btf::read(path);
        ADD_FAILURE() << "read succeeded; expected an error about " << field;
    } catch (const SceneError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(path), std::string::npos) << what;
        EXPECT_NE(what.find(field), std::string::npos) << what;
    }
}

void put_u32(std::string& bytes, size_t offset, uint32_t value) {
    std::memcpy(bytes.data() + offset, &value, 4);
}

// Layout of the synthetic files: a 10-byte signature, 291 bytes of meta data, the sampling
// (4 + views x (12 + 8 lights) bytes), then width and height.
constexpr size_t kMetaStart = 10, kSamplingStart = 10 + 291;
constexpr size_t kWidthOffset = kSamplingStart + 4 + 81 * (12 + 8 * 81);

TEST(BtfFile, BadFilesAreLocatedErrors) {
    const std::string bdi = file_bytes(write_synth(small_options(btf::Format::Bdi), "ok.bdi"));
    const std::string dfmf = file_bytes(write_synth(small_options(btf::Format::Dfmf), "ok.dfmf"));
    expect_bad("#not a btf at all", "signature");
    expect_bad("!PVF06FC" + std::string(100, '\0'), "PVF");
    expect_bad(bdi.substr(0, 5), "signature");
    expect_bad(bdi.substr(0, 200), "truncated");
    expect_bad(bdi.substr(0, kWidthOffset + 2), "width");
    expect_bad(bdi.substr(0, bdi.size() - 1), "chunk");
    expect_bad(dfmf.substr(0, dfmf.size() / 2), "channel");
    expect_bad(bdi + "x", "end of file");
    std::string b = bdi;
    put_u32(b, kMetaStart, 12345);
    expect_bad(b, "meta data size");
    b = bdi;
    put_u32(b, kSamplingStart, 0xFFFFFFFFu);
    expect_bad(b, "view count");
    b = bdi;
    put_u32(b, kSamplingStart + 4 + 8, 80);  // view 0 lists 80 lights
    expect_bad(b, "light count");
    b = bdi;
    put_u32(b, kWidthOffset, 0xFFFFFFFFu);
    expect_bad(b, "width");
    b = bdi;
    put_u32(b, kWidthOffset + 8, 2);  // 2 scan lines per chunk: the chunks' sizes disagree
    expect_bad(b, "chunk 0");
    b = bdi;
    put_u32(b, kWidthOffset + 8, 5);  // more scan lines per chunk than the texture has
    expect_bad(b, "scan lines");
    b = dfmf;
    // After width, height, rotations, components, model, mean and matrix: channel 0's sizes.
    const size_t channel0 = kWidthOffset + 8 + 4 + 4 + 4 + 12 + 36;
    put_u32(b, channel0 + 1, 0x7FFFFFFFu);  // an absurd component count
    expect_bad(b, "channel 0");
    b = dfmf;
    put_u32(b, channel0 + 1 + 4, 81 * 80);  // rows that do not match the sampling
    expect_bad(b, "channel 0");
}

TEST(BtfFile, MissingAndNonRegularFilesAreErrors) {
    EXPECT_THROW(btf::read("/nonexistent/femto/file.btf"), SceneError);
    EXPECT_THROW(btf::read(femto::testing::temp_dir("btf-dir").string()), SceneError);
    EXPECT_THROW(btf::read(write_bytes("", "empty.btf")), SceneError);
}

TEST(BtfFile, RandomCorruptionNeverCrashes) {
    // Flipped bytes anywhere in the header or the data: the reader either reads a file (whose
    // values are then finite or not, as the bytes say) or throws a SceneError.
    const std::string good = file_bytes(write_synth(small_options(btf::Format::Dfmf), "c.dfmf"));
    std::mt19937 rng(7);
    int errors = 0;
    for (int trial = 0; trial < 300; ++trial) {
        std::string b = good;
        const size_t span = trial % 2 ? b.size() : kWidthOffset + 200;
        for (int k = 0; k < 4; ++k) b[rng() % span] = char(rng());
        try {
            const auto data = btf::read(write_bytes(b, "corrupt.btf"));
            data->value(0, 0, 0, 0);
        } catch (const SceneError&) {
            ++errors;
        }
    }
    EXPECT_GT(errors, 0);
}

}  // namespace
