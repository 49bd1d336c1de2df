#include "femto/warp.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <stdexcept>

namespace femto::warp {

namespace {

// Picks a when `pick_a`, else b, through bit masks: compilers turn a ternary between floats
// into a branch, and here the choice is a coin flip per sample, mispredicted half the time.
inline float select(bool pick_a, float a, float b) {
    const uint32_t mask = 0u - uint32_t(pick_a);
    return std::bit_cast<float>((std::bit_cast<uint32_t>(a) & mask) |
                                (std::bit_cast<uint32_t>(b) & ~mask));
}

// sin and cos of x in [-pi/4, pi/4], where their Taylor series to x^9 and x^10 are within 1.1
// ulps (measured over 2^21 angles; WarpDisk.ConcentricMapMatchesItsClosedFormToTheUlp checks
// the map they serve): no call, no range reduction.
inline Vec2 quarter_cos_sin(float x) {
    const float x2 = x * x;
    const float s =
        x * (1.f + x2 * (-1.f / 6 + x2 * (1.f / 120 + x2 * (-1.f / 5040 + x2 * (1.f / 362880)))));
    const float c =
        1.f + x2 * (-0.5f + x2 * (1.f / 24 +
                                  x2 * (-1.f / 720 + x2 * (1.f / 40320 + x2 * (-1.f / 3628800)))));
    return {c, s};
}

}  // namespace

Vec2 square_to_uniform_disk(Vec2 u) {
    const float a = 2.f * u.x - 1.f, b = 2.f * u.y - 1.f;
    if (a == 0 && b == 0) return {0, 0};
    // Wedge |a| > |b|: radius a, angle (pi/4) b/a. Otherwise radius b, angle
    // pi/2 - (pi/4) a/b, whose cosine and sine are the sine and cosine of (pi/4) a/b.
    const bool wide = a * a > b * b;
    const float r = select(wide, a, b);
    const Vec2 cs = quarter_cos_sin((kPi / 4.f) * (select(wide, b, a) / r));
    return {r * select(wide, cs.x, cs.y), r * select(wide, cs.y, cs.x)};
}

Vec3 square_to_cosine_hemisphere(Vec2 u) {
    const Vec2 d = square_to_uniform_disk(u);
    const float z = safe_sqrt(1.f - d.x * d.x - d.y * d.y);
    return {d.x, d.y, z};
}

Vec3 square_to_uniform_hemisphere(Vec2 u) {
    const float z = u.x;
    const float r = safe_sqrt(1.f - z * z), phi = 2.f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

Vec3 square_to_uniform_sphere(Vec2 u) {
    const float z = 1.f - 2.f * u.x;
    const float r = safe_sqrt(1.f - z * z), phi = 2.f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

Vec3 square_to_uniform_cone(Vec2 u, float cos_max) {
    const float z = 1.f - u.x * (1.f - cos_max);
    const float r = safe_sqrt(1.f - z * z), phi = 2.f * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

uint32_t sample_discrete_cdf(const float* cdf, uint32_t n, float& u) {
    // First index i with cdf[i+1] > u.
    const float* it = std::upper_bound(cdf + 1, cdf + n + 1, u);
    uint32_t i =
        static_cast<uint32_t>(std::min<std::ptrdiff_t>(it - (cdf + 1), std::ptrdiff_t(n) - 1));
    while (i > 0 && cdf[i + 1] - cdf[i] <= 0) --i;  // never pick an empty interval
    const float width = cdf[i + 1] - cdf[i];
    u = width > 0 ? std::min((u - cdf[i]) / width, 0x1.fffffep-1f) : 0.f;
    return i;
}

AliasTable::AliasTable(const std::vector<double>& weights) {
    const size_t n = weights.size();
    double sum = 0;
    for (double w : weights) {
        if (!(w >= 0) || !std::isfinite(w))
            throw std::invalid_argument("alias table: a weight is negative or not finite");
        sum += w;
    }
    if (!(sum > 0) || !std::isfinite(sum))
        throw std::invalid_argument("alias table: the weights do not have a positive sum");
    // Vose: cells below the mean borrow from cells above it, one donor per cell, in a fixed
    // order (the table depends on the weights alone).
    std::vector<double> scaled(n);
    std::vector<uint32_t> small, large;
    for (size_t i = 0; i < n; ++i) {
        scaled[i] = weights[i] * double(n) / sum;
        (scaled[i] < 1.0 ? small : large).push_back(uint32_t(i));
    }
    entries_.assign(n, Cell{});
    for (size_t i = 0; i < n; ++i) entries_[i].alias = uint32_t(i);
    while (!small.empty() && !large.empty()) {
        const uint32_t s = small.back(), l = large.back();
        small.pop_back();
        entries_[s] = {float(scaled[s]), l};
        scaled[l] -= 1.0 - scaled[s];
        if (scaled[l] < 1.0) {
            large.pop_back();
            small.push_back(l);
        }
    }
    // What is left is 1 up to rounding: such cells keep their own index throughout. A cell
    // of weight 0 left here by rounding must still never be chosen: it gives its alias.
    for (uint32_t i : small) entries_[i].threshold = weights[i] > 0 ? 1.f : 0.f;
    for (uint32_t i : large) entries_[i].threshold = 1.f;
    for (size_t i = 0; i < n; ++i)
        if (weights[i] == 0) entries_[i].threshold = 0.f;
    // A weight-0 cell's alias must have weight: point such cells at the heaviest entry.
    const uint32_t heaviest =
        uint32_t(std::max_element(weights.begin(), weights.end()) - weights.begin());
    for (Cell& c : entries_) {
        if (weights[c.alias] == 0) c.alias = heaviest;
        c.inv_threshold = c.threshold > 0 ? 1.f / c.threshold : 0.f;
        c.inv_rest = c.threshold < 1 ? 1.f / (1.f - c.threshold) : 0.f;
    }
}

}  // namespace femto::warp
