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

/// sRGB transfer function (used for `srgb` values in scenes).
inline float srgb_to_linear(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

}  // namespace femto
