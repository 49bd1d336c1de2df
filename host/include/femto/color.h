// femto public API: linear RGB colour (Rec.709 primaries, the `rgb` intent of Mitsuba).
#pragma once

#include <algorithm>
#include <cmath>

namespace femto {

struct Color {
    float r = 0, g = 0, b = 0;
    constexpr Color() = default;
    constexpr Color(float r_, float g_, float b_) : r(r_), g(g_), b(b_) {}
    constexpr explicit Color(float v) : r(v), g(v), b(v) {}
    constexpr float operator[](int i) const { return i == 0 ? r : (i == 1 ? g : b); }
    constexpr float& operator[](int i) { return i == 0 ? r : (i == 1 ? g : b); }
    constexpr Color operator+(const Color& o) const { return {r + o.r, g + o.g, b + o.b}; }
    constexpr Color operator-(const Color& o) const { return {r - o.r, g - o.g, b - o.b}; }
    constexpr Color operator*(const Color& o) const { return {r * o.r, g * o.g, b * o.b}; }
    constexpr Color operator/(const Color& o) const { return {r / o.r, g / o.g, b / o.b}; }
    constexpr Color operator*(float s) const { return {r * s, g * s, b * s}; }
    constexpr Color operator/(float s) const { return {r / s, g / s, b / s}; }
    constexpr Color& operator+=(const Color& o) {
        r += o.r;
        g += o.g;
        b += o.b;
        return *this;
    }
    constexpr Color& operator*=(const Color& o) {
        r *= o.r;
        g *= o.g;
        b *= o.b;
        return *this;
    }
    constexpr Color& operator*=(float s) {
        r *= s;
        g *= s;
        b *= s;
        return *this;
    }
    constexpr bool operator==(const Color& o) const { return r == o.r && g == o.g && b == o.b; }
    constexpr bool is_black() const { return r == 0 && g == 0 && b == 0; }
    constexpr float max_component() const { return std::max({r, g, b}); }
    constexpr float average() const { return (r + g + b) * (1.f / 3.f); }
    /// Rec.709 luminance.
    constexpr float luminance() const { return 0.212671f * r + 0.715160f * g + 0.072169f * b; }
    bool is_finite() const { return std::isfinite(r) && std::isfinite(g) && std::isfinite(b); }
};
constexpr Color operator*(float s, const Color& c) { return c * s; }

/// A 3x3 matrix acting on colours (L_out = M L_in), for materials that move energy between
/// channels, such as fluorescence.
struct ColorMatrix {
    float m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};  ///< identity by default

    constexpr Color operator*(const Color& c) const {
        return {m[0][0] * c.r + m[0][1] * c.g + m[0][2] * c.b,
                m[1][0] * c.r + m[1][1] * c.g + m[1][2] * c.b,
                m[2][0] * c.r + m[2][1] * c.g + m[2][2] * c.b};
    }
    constexpr ColorMatrix operator*(const ColorMatrix& o) const {
        ColorMatrix r;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                r.m[i][j] = m[i][0] * o.m[0][j] + m[i][1] * o.m[1][j] + m[i][2] * o.m[2][j];
        return r;
    }
    /// this * diag(c)
    constexpr ColorMatrix scale_columns(const Color& c) const {
        ColorMatrix r = *this;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) r.m[i][j] *= c[j];
        return r;
    }
    /// Largest row sum: how much a unit white input can produce in one channel.
    constexpr float max_row_sum() const {
        return std::max({m[0][0] + m[0][1] + m[0][2], m[1][0] + m[1][1] + m[1][2],
                         m[2][0] + m[2][1] + m[2][2]});
    }
};

/// sRGB transfer function (used for `srgb` values in scenes).
inline float srgb_to_linear(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

}  // namespace femto
