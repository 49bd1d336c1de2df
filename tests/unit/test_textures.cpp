// Tests of the texture plugins: checkerboard (Mitsuba 3 semantics, to_uv, nested textures)
// and bitmap (nearest/bilinear filtering, sRGB decoding vs raw, wrap modes, the v flip,
// float images, bad parameters and missing files). The bitmap tests write their own tiny
// binary PPM and PFM images.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "femto/color.h"
#include "femto/host.h"
#include "femto/texture.h"
#include "femto/transform.h"

namespace {

using femto::Color;
using femto::PluginKind;
using femto::Properties;
using femto::Texture;

std::shared_ptr<Texture> make_texture(const Properties& props) {
    femto::ObjectPtr obj = femto::create_object(PluginKind::Texture, props.plugin_type(), props);
    EXPECT_TRUE(obj);
    EXPECT_EQ(obj->kind(), PluginKind::Texture);
    return std::static_pointer_cast<Texture>(obj);
}

Color at(const Texture& t, float u, float v) {
    femto::Hit hit;
    hit.uv = femto::Vec2(u, v);
    return t.eval(hit);
}

::testing::AssertionResult color_near(const Color& actual, const Color& expected, float tol) {
    for (int k = 0; k < 3; ++k)
        if (!(std::abs(actual[k] - expected[k]) <= tol))
            return ::testing::AssertionFailure()
                   << "got (" << actual.r << ", " << actual.g << ", " << actual.b << "), expected ("
                   << expected.r << ", " << expected.g << ", " << expected.b << ") +- " << tol;
    return ::testing::AssertionSuccess();
}
#define EXPECT_COLOR_NEAR(actual, expected, tol) \
    EXPECT_TRUE(color_near((actual), (expected), (tol)))

// -- checkerboard -----------------------------------------------------------------------------

TEST(TextureCheckerboard, MitsubaDefaults) {
    auto t = make_texture(Properties("checkerboard", {}));
    const Color c0(0.4f), c1(0.2f);
    EXPECT_EQ(at(*t, 0.25f, 0.25f), c0);
    EXPECT_EQ(at(*t, 0.75f, 0.75f), c0);
    EXPECT_EQ(at(*t, 0.75f, 0.25f), c1);
    EXPECT_EQ(at(*t, 0.25f, 0.75f), c1);
    // 0.5 itself is on the "<= 0.5" side.
    EXPECT_EQ(at(*t, 0.5f, 0.25f), c0);
    EXPECT_EQ(at(*t, 0.5f, 0.75f), c1);
    // u and v are wrapped to [0, 1): the pattern repeats with period 1.
    EXPECT_EQ(at(*t, 1.25f, -0.75f), c0);
    EXPECT_EQ(at(*t, -0.25f, 0.25f), c1);
    EXPECT_EQ(at(*t, 7.75f, -3.75f), c1);
    EXPECT_EQ(at(*t, 7.75f, -3.25f), c0);
    EXPECT_EQ(at(*t, 0.f, 0.f), c0);
    EXPECT_EQ(at(*t, 1.f, 1.f), c0);
    EXPECT_COLOR_NEAR(t->mean(), Color(0.3f), 1e-7f);
    EXPECT_FALSE(t->is_constant());
}

TEST(TextureCheckerboard, ColoursAndToUv) {
    Properties props("checkerboard", {});
    props.set_color("color0", Color(1.f, 0.5f, 0.f));
    props.set_color("color1", Color(0.f, 0.25f, 1.f));
    props.set_transform("to_uv", femto::Transform::scale(femto::Vec3(2.f, 4.f, 1.f)));
    auto t = make_texture(props);
    // (0.3, 0.1) -> (0.6, 0.4): u > 0.5, v <= 0.5 -> color1.
    EXPECT_EQ(at(*t, 0.3f, 0.1f), Color(0.f, 0.25f, 1.f));
    // (0.1, 0.1) -> (0.2, 0.4) -> color0; (0.1, 0.2) -> (0.2, 0.8) -> color1.
    EXPECT_EQ(at(*t, 0.1f, 0.1f), Color(1.f, 0.5f, 0.f));
    EXPECT_EQ(at(*t, 0.1f, 0.2f), Color(0.f, 0.25f, 1.f));
    // (0.4, 0.2) -> (0.8, 0.8) -> color0.
    EXPECT_EQ(at(*t, 0.4f, 0.2f), Color(1.f, 0.5f, 0.f));
    EXPECT_COLOR_NEAR(t->mean(), Color(0.5f, 0.375f, 0.5f), 1e-7f);

    // A translation moves the pattern (to_uv is applied to the point (u, v, 0)).
    Properties shifted("checkerboard", {});
    shifted.set_transform("to_uv", femto::Transform::translate(femto::Vec3(0.5f, 0.f, 0.f)));
    auto s = make_texture(shifted);
    EXPECT_EQ(at(*s, 0.25f, 0.25f), Color(0.2f));
    EXPECT_EQ(at(*s, 0.75f, 0.25f), Color(0.4f));
}

TEST(TextureCheckerboard, NestedTexture) {
    Properties inner("checkerboard", {});
    inner.set_color("color0", Color(1.f));
    inner.set_color("color1", Color(0.f));
    inner.set_transform("to_uv", femto::Transform::scale(femto::Vec3(2.f, 2.f, 1.f)));
    Properties outer("checkerboard", {});
    outer.set_object("color0", femto::create_object(PluginKind::Texture, "checkerboard", inner));
    outer.set_color("color1", Color(0.5f));
    auto t = make_texture(outer);
    // Inside the outer color0 square [0, .5]^2 the inner checker has period 0.5.
    EXPECT_EQ(at(*t, 0.1f, 0.1f), Color(1.f));   // inner (0.2, 0.2)
    EXPECT_EQ(at(*t, 0.4f, 0.1f), Color(0.f));   // inner (0.8, 0.2)
    EXPECT_EQ(at(*t, 0.6f, 0.1f), Color(0.5f));  // outer color1
    EXPECT_COLOR_NEAR(t->mean(), Color(0.5f * 0.5f + 0.5f * 0.5f), 1e-7f);
}

TEST(TextureCheckerboard, SchemaAndUnknownParameter) {
    const femto::PluginDescriptor& d = femto::find_plugin(PluginKind::Texture, "checkerboard");
    std::vector<std::string> names;
    for (const auto& p : d.params) names.push_back(p.name);
    EXPECT_EQ(names, (std::vector<std::string>{"color0", "color1", "to_uv"}));
    Properties props("checkerboard", {});
    props.set_color("colour0", Color(1.f));
    EXPECT_THROW(make_texture(props), femto::SceneError);
}

// -- bitmap -----------------------------------------------------------------------------------

// A 3 x 2 8-bit image, rows top to bottom: A B C / D E F.
constexpr int kW = 3, kH = 2;
constexpr std::array<std::array<uint8_t, 3>, 6> kPixels = {
    {{10, 20, 30}, {40, 50, 60}, {70, 80, 90}, {100, 110, 120}, {130, 140, 150}, {160, 210, 250}}};

/// Texel (i, j) with j counted from the bottom row, as a colour (raw or sRGB-decoded).
Color texel(int i, int j, bool raw) {
    const auto& p = kPixels[(kH - 1 - j) * kW + i];
    Color c;
    for (int k = 0; k < 3; ++k) {
        const float v = p[k] / 255.f;
        c[k] = raw ? v : femto::srgb_to_linear(v);
    }
    return c;
}

class TextureBitmap : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = std::filesystem::temp_directory_path() /
               ("femto_test_textures_" + std::to_string(::getpid()) + "_" + info->name());
        std::filesystem::create_directories(dir_);

        ppm_ = (dir_ / "image.ppm").string();
        std::ofstream ppm(ppm_, std::ios::binary);
        ppm << "P6\n" << kW << " " << kH << "\n255\n";
        for (const auto& p : kPixels) ppm.write(reinterpret_cast<const char*>(p.data()), 3);
        ASSERT_TRUE(ppm.good());

        // PFM: scanlines are stored bottom to top; the scale's sign gives the byte order.
        pfm_ = (dir_ / "image.pfm").string();
        std::ofstream pfm(pfm_, std::ios::binary);
        pfm << "PF\n2 2\n" << (std::endian::native == std::endian::little ? "-1.0" : "1.0") << "\n";
        const float data[12] = {1.5f, 2.f, 3.f, 4.f,  5.f,   6.25f,    // bottom row
                                7.f,  8.f, 9.f, 10.f, 11.5f, 0.125f};  // top row
        pfm.write(reinterpret_cast<const char*>(data), sizeof(data));
        ASSERT_TRUE(pfm.good());
    }
    void TearDown() override {
        std::error_code ec;
        std::filesystem::remove_all(dir_, ec);
    }

    std::shared_ptr<Texture> load(const std::string& file, const std::string& filter,
                                  const std::string& wrap = "", int raw = -1) const {
        Properties props("bitmap", {});
        props.set_string("filename", file);
        if (!filter.empty()) props.set_string("filter_type", filter);
        if (!wrap.empty()) props.set_string("wrap_mode", wrap);
        if (raw >= 0) props.set_bool("raw", raw != 0);
        return make_texture(props);
    }

    /// uv of the centre of texel (i, j), j from the bottom.
    static float cu(float i) { return (i + 0.5f) / kW; }
    static float cv(float j) { return (j + 0.5f) / kH; }

    std::filesystem::path dir_;
    std::string ppm_, pfm_;
};

constexpr float kTol = 2e-4f;

TEST_F(TextureBitmap, NearestRawValuesAndVerticalFlip) {
    auto t = load(ppm_, "nearest", "", 1);
    for (int j = 0; j < kH; ++j)
        for (int i = 0; i < kW; ++i)
            EXPECT_COLOR_NEAR(at(*t, cu(i), cv(j)), texel(i, j, true), kTol) << i << "," << j;
    // v = 0 is the bottom row (D E F), v -> 1 the top row (A B C).
    EXPECT_COLOR_NEAR(at(*t, 0.05f, 0.05f), Color(100 / 255.f, 110 / 255.f, 120 / 255.f), kTol);
    EXPECT_COLOR_NEAR(at(*t, 0.05f, 0.95f), Color(10 / 255.f, 20 / 255.f, 30 / 255.f), kTol);
    EXPECT_COLOR_NEAR(at(*t, 0.95f, 0.05f), Color(160 / 255.f, 210 / 255.f, 250 / 255.f), kTol);
    // Anywhere inside a texel gives that texel.
    EXPECT_COLOR_NEAR(at(*t, 0.34f, 0.49f), texel(1, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*t, 0.66f, 0.51f), texel(1, 1, true), kTol);
    // mean = average pixel
    Color mean;
    for (int j = 0; j < kH; ++j)
        for (int i = 0; i < kW; ++i) mean += texel(i, j, true) / 6.f;
    EXPECT_COLOR_NEAR(t->mean(), mean, kTol);
    EXPECT_FALSE(t->is_constant());
}

TEST_F(TextureBitmap, EightBitImagesAreSrgbDecodedUnlessRaw) {
    auto decoded = load(ppm_, "nearest");  // raw defaults to false
    auto raw = load(ppm_, "nearest", "", 1);
    for (int j = 0; j < kH; ++j)
        for (int i = 0; i < kW; ++i) {
            const Color d = at(*decoded, cu(i), cv(j)), r = at(*raw, cu(i), cv(j));
            EXPECT_COLOR_NEAR(d, texel(i, j, false), kTol);
            for (int k = 0; k < 3; ++k) {
                EXPECT_NEAR(femto::srgb_to_linear(r[k]), d[k], kTol);
                EXPECT_LT(d[k], r[k]);  // sRGB decoding darkens mid-tones
            }
        }
    // 160/255 = 0.627 in sRGB is 0.352 linear.
    EXPECT_NEAR(at(*decoded, cu(2), cv(0)).r, 0.3515f, 1e-3f);
    Color mean;
    for (int j = 0; j < kH; ++j)
        for (int i = 0; i < kW; ++i) mean += texel(i, j, false) / 6.f;
    EXPECT_COLOR_NEAR(decoded->mean(), mean, kTol);
}

TEST_F(TextureBitmap, BilinearInterpolatesTexelCentres) {
    auto t = load(ppm_, "", "clamp", 1);  // bilinear is the default
    for (int j = 0; j < kH; ++j)
        for (int i = 0; i < kW; ++i)
            EXPECT_COLOR_NEAR(at(*t, cu(i), cv(j)), texel(i, j, true), kTol);
    // Halfway between D and E (bottom row).
    EXPECT_COLOR_NEAR(at(*t, cu(0.5f), cv(0)), (texel(0, 0, true) + texel(1, 0, true)) * 0.5f,
                      kTol);
    // Halfway between E (bottom) and B (top): the image centre.
    EXPECT_COLOR_NEAR(at(*t, 0.5f, 0.5f), (texel(1, 0, true) + texel(1, 1, true)) * 0.5f, kTol);
    // A general point: a quarter of the way from texel (1,0) to (2,0), 3/4 towards the top.
    const Color expected = (texel(1, 0, true) * 0.75f + texel(2, 0, true) * 0.25f) * 0.25f +
                           (texel(1, 1, true) * 0.75f + texel(2, 1, true) * 0.25f) * 0.75f;
    EXPECT_COLOR_NEAR(at(*t, cu(1.25f), cv(0.75f)), expected, kTol);
    // Nearest differs from bilinear off the texel centres.
    auto n = load(ppm_, "nearest", "clamp", 1);
    EXPECT_COLOR_NEAR(at(*n, cu(1.25f), cv(0.75f)), texel(1, 1, true), kTol);
}

TEST_F(TextureBitmap, WrapModesNearest) {
    auto rep = load(ppm_, "nearest", "repeat", 1);
    auto mir = load(ppm_, "nearest", "mirror", 1);
    auto cla = load(ppm_, "nearest", "clamp", 1);
    const float v0 = cv(0);
    // Column -1 (u slightly below 0): repeat -> last column, mirror/clamp -> first.
    EXPECT_COLOR_NEAR(at(*rep, -0.1f, v0), texel(2, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*mir, -0.1f, v0), texel(0, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*cla, -0.1f, v0), texel(0, 0, true), kTol);
    // Column 3 (just past u = 1): repeat -> first, mirror/clamp -> last.
    EXPECT_COLOR_NEAR(at(*rep, 1.1f, v0), texel(0, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*mir, 1.1f, v0), texel(2, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*cla, 1.1f, v0), texel(2, 0, true), kTol);
    // Column 4: repeat -> 1, mirror -> 1, clamp -> 2. Column 5: repeat 2, mirror 0, clamp 2.
    EXPECT_COLOR_NEAR(at(*rep, cu(4), v0), texel(1, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*mir, cu(4), v0), texel(1, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*cla, cu(4), v0), texel(2, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*rep, cu(5), v0), texel(2, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*mir, cu(5), v0), texel(0, 0, true), kTol);
    // Far away: repeat has period 1, mirror period 2.
    EXPECT_COLOR_NEAR(at(*rep, cu(1) + 17.f, cv(1) - 5.f), texel(1, 1, true), kTol);
    EXPECT_COLOR_NEAR(at(*mir, cu(1) + 18.f, cv(1) - 6.f), texel(1, 1, true), kTol);
    EXPECT_COLOR_NEAR(at(*mir, cu(0) + 1.f, cv(0)), texel(2, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*cla, cu(1) + 17.f, cv(1) - 5.f), texel(2, 0, true), kTol);
    // Row -1 (v below 0): repeat -> top row, mirror/clamp -> bottom row. Row 2: the reverse.
    EXPECT_COLOR_NEAR(at(*rep, cu(1), -0.25f), texel(1, 1, true), kTol);
    EXPECT_COLOR_NEAR(at(*mir, cu(1), -0.25f), texel(1, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*cla, cu(1), -0.25f), texel(1, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*rep, cu(1), 1.25f), texel(1, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*mir, cu(1), 1.25f), texel(1, 1, true), kTol);
    EXPECT_COLOR_NEAR(at(*cla, cu(1), 1.25f), texel(1, 1, true), kTol);
    // u = 1 exactly is column 0 again under repeat (uv wrap to [0, 1)).
    EXPECT_COLOR_NEAR(at(*rep, 1.f, v0), texel(0, 0, true), kTol);
}

TEST_F(TextureBitmap, WrapModesBilinearAtTheBorder) {
    // At u = 0 the filter straddles column -1 and column 0 equally.
    const float v0 = cv(0);
    auto rep = load(ppm_, "bilinear", "repeat", 1);
    auto mir = load(ppm_, "bilinear", "mirror", 1);
    auto cla = load(ppm_, "bilinear", "clamp", 1);
    EXPECT_COLOR_NEAR(at(*rep, 0.f, v0), (texel(2, 0, true) + texel(0, 0, true)) * 0.5f, kTol);
    EXPECT_COLOR_NEAR(at(*mir, 0.f, v0), texel(0, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*cla, 0.f, v0), texel(0, 0, true), kTol);
    // At v = 1 the filter straddles the top row and row 2.
    EXPECT_COLOR_NEAR(at(*rep, cu(1), 1.f), (texel(1, 1, true) + texel(1, 0, true)) * 0.5f, kTol);
    EXPECT_COLOR_NEAR(at(*cla, cu(1), 1.f), texel(1, 1, true), kTol);
    // Repeat is seamless: u and u + 1 agree.
    for (float u : {0.f, 0.1f, 0.37f, 0.9f})
        EXPECT_COLOR_NEAR(at(*rep, u + 1.f, 0.3f), at(*rep, u, 0.3f), kTol);
}

TEST_F(TextureBitmap, ToUvTransform) {
    Properties props("bitmap", {});
    props.set_string("filename", ppm_);
    props.set_string("filter_type", "nearest");
    props.set_bool("raw", true);
    props.set_transform("to_uv", femto::Transform::scale(femto::Vec3(0.5f, 1.f, 1.f)));
    auto t = make_texture(props);
    // u = 0.9 -> 0.45: the middle column.
    EXPECT_COLOR_NEAR(at(*t, 0.9f, cv(0)), texel(1, 0, true), kTol);
    EXPECT_COLOR_NEAR(at(*t, 0.1f, cv(1)), texel(0, 1, true), kTol);
}

TEST_F(TextureBitmap, FloatImagesAreLinear) {
    // The PFM stores the bottom row first: (1.5 2 3) (4 5 6.25) / top (7 8 9) (10 11.5 0.125).
    for (int raw : {0, 1}) {
        SCOPED_TRACE(raw);
        auto t = load(pfm_, "nearest", "", raw);
        EXPECT_COLOR_NEAR(at(*t, 0.25f, 0.25f), Color(1.5f, 2.f, 3.f), 1e-6f);
        EXPECT_COLOR_NEAR(at(*t, 0.75f, 0.25f), Color(4.f, 5.f, 6.25f), 1e-6f);
        EXPECT_COLOR_NEAR(at(*t, 0.25f, 0.75f), Color(7.f, 8.f, 9.f), 1e-6f);
        EXPECT_COLOR_NEAR(at(*t, 0.75f, 0.75f), Color(10.f, 11.5f, 0.125f), 1e-6f);
        const Color mean(22.5f / 4, 26.5f / 4, 18.375f / 4);
        EXPECT_COLOR_NEAR(t->mean(), mean, 1e-5f);
        auto b = load(pfm_, "bilinear", "", raw);
        EXPECT_COLOR_NEAR(at(*b, 0.5f, 0.5f), mean, 1e-5f);
        EXPECT_COLOR_NEAR(at(*b, 0.5f, 0.25f), Color(2.75f, 3.5f, 4.625f), 1e-5f);
    }
}

TEST_F(TextureBitmap, BadInput) {
    const std::string missing = (dir_ / "no_such_image.png").string();
    try {
        load(missing, "");
        ADD_FAILURE() << "a missing file must be a SceneError";
    } catch (const femto::SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("no_such_image.png"), std::string::npos) << e.what();
    }
    EXPECT_THROW(load(dir_.string(), ""), femto::SceneError);  // a folder, not an image
    const std::string garbage = (dir_ / "garbage.png").string();
    std::ofstream(garbage) << "this is not a PNG file\n";
    EXPECT_THROW(load(garbage, ""), femto::SceneError);
    EXPECT_THROW(load(ppm_, "cubic"), femto::SceneError);
    EXPECT_THROW(load(ppm_, "", "wrap"), femto::SceneError);
    Properties no_file("bitmap", {});
    EXPECT_THROW(make_texture(no_file), femto::SceneError);
}

// The message of the SceneError that loading `file` gives, and what was printed meanwhile.
std::pair<std::string, std::string> bitmap_error(const std::string& file) {
    Properties props("bitmap", {"scene.xml", 7, 3});
    props.set("filename", Properties::Type::String, file, {"scene.xml", 8, 5});
    ::testing::internal::CaptureStderr();
    std::string what;
    try {
        make_texture(props);
        ADD_FAILURE() << file << ": no error";
    } catch (const femto::SceneError& e) {
        what = e.what();
    }
    return {what, ::testing::internal::GetCapturedStderr()};
}

size_t count(const std::string& text, const std::string& part) {
    size_t n = 0;
    for (size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++n;
    return n;
}

// A corrupt image gives one located error that says once which file it is, and nothing else
// on stderr (libpng prints its own "libpng error:" lines, which femto keeps back).
TEST_F(TextureBitmap, CorruptImageGivesOneCleanError) {
    const std::string png = (dir_ / "corrupt.png").string();
    std::ofstream(png, std::ios::binary)
        << std::string("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\0\x02\0\0\0\x02\x08\x02\0\0\0BAD!", 33);
    const auto [what, printed] = bitmap_error(png);
    EXPECT_NE(what.find("scene.xml:8:5: \"bitmap\": cannot read image \"" + png + "\": "),
              std::string::npos)
        << what;
    EXPECT_EQ(count(what, "cannot read image"), 1u) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(printed, "");
}

// OpenEXR would allocate scanline buffers for the width a header claims (1.4 GB here) before
// femto sees the size: such a header is refused first.
TEST_F(TextureBitmap, HugeExrDataWindowIsRefusedAtTheHeader) {
    auto attribute = [](const std::string& name, const std::string& type, const std::string& data) {
        const uint32_t size = uint32_t(data.size());
        std::string a = name + '\0' + type + '\0';
        a.append(reinterpret_cast<const char*>(&size), 4);
        return a + data;
    };
    auto ints = [](std::initializer_list<int32_t> v) {
        return std::string(reinterpret_cast<const char*>(std::data(v)), v.size() * 4);
    };
    const float one = 1.f, zero2[2] = {0.f, 0.f};
    std::string exr("\x76\x2f\x31\x01\x02\0\0\0", 8);
    exr += attribute("channels", "chlist", std::string("R\0", 2) + ints({1, 0, 1, 1}) + '\0');
    exr += attribute("compression", "compression", std::string(1, '\0'));
    exr += attribute("dataWindow", "box2i", ints({0, 0, 240'000'000, 15}));
    exr += attribute("displayWindow", "box2i", ints({0, 0, 240'000'000, 15}));
    exr += attribute("lineOrder", "lineOrder", std::string(1, '\0'));
    exr +=
        attribute("pixelAspectRatio", "float", std::string(reinterpret_cast<const char*>(&one), 4));
    exr += attribute("screenWindowCenter", "v2f",
                     std::string(reinterpret_cast<const char*>(zero2), 8));
    exr += attribute("screenWindowWidth", "float",
                     std::string(reinterpret_cast<const char*>(&one), 4));
    exr += '\0';
    const std::string path = (dir_ / "huge.exr").string();
    std::ofstream(path, std::ios::binary) << exr;
    const auto [what, printed] = bitmap_error(path);
    EXPECT_NE(what.find("exceeds the maximum width of 65536"), std::string::npos) << what;
    EXPECT_EQ(count(what, "cannot read image"), 1u) << what;
}

// Negative (or NaN) texels would make negative radiance: they are read as 0, with a warning.
TEST_F(TextureBitmap, NegativeTexelsAreReadAsZero) {
    const std::string pfm = (dir_ / "negative.pfm").string();
    std::ofstream out(pfm, std::ios::binary);
    out << "PF\n2 1\n" << (std::endian::native == std::endian::little ? "-1.0" : "1.0") << "\n";
    const float data[6] = {-0.5f, 0.25f, 1.f, 0.5f, std::nanf(""), -2.f};
    out.write(reinterpret_cast<const char*>(data), sizeof(data));
    out.close();
    Properties props("bitmap", {});
    props.set_string("filename", pfm);
    ::testing::internal::CaptureStderr();
    auto t = make_texture(props);
    const std::string printed = ::testing::internal::GetCapturedStderr();
    EXPECT_NE(printed.find("has 3 negative or non-finite channel values; they are read as 0"),
              std::string::npos)
        << printed;
    EXPECT_COLOR_NEAR(at(*t, 0.25f, 0.5f), Color(0.f, 0.25f, 1.f), 1e-6f);
    EXPECT_COLOR_NEAR(at(*t, 0.75f, 0.5f), Color(0.5f, 0.f, 0.f), 1e-6f);
}

TEST(TextureBitmapSchema, ParametersAreDocumented) {
    const femto::PluginDescriptor& d = femto::find_plugin(PluginKind::Texture, "bitmap");
    std::vector<std::string> names;
    for (const auto& p : d.params) names.push_back(p.name);
    EXPECT_EQ(names,
              (std::vector<std::string>{"filename", "raw", "filter_type", "wrap_mode", "to_uv"}));
}

}  // namespace
