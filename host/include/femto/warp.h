// femto public API: sampling routines mapping [0,1)^2 to directions and points, with pdfs.
// Each has a chi-square test against its pdf in tests/unit/test_warp_chi2.cpp.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "femto/math.h"

namespace femto::warp {

/// Concentric map to the unit disk (Shirley & Chiu); pdf 1/pi.
Vec2 square_to_uniform_disk(Vec2 u);
/// Cosine-weighted hemisphere around +z; pdf cos(theta)/pi.
Vec3 square_to_cosine_hemisphere(Vec2 u);
inline float cosine_hemisphere_pdf(const Vec3& v) { return v.z > 0 ? v.z * kInvPi : 0.f; }
/// Uniform hemisphere around +z; pdf 1/(2 pi).
Vec3 square_to_uniform_hemisphere(Vec2 u);
inline float uniform_hemisphere_pdf(const Vec3& v) { return v.z >= 0 ? kInvTwoPi : 0.f; }
/// Uniform sphere; pdf 1/(4 pi).
Vec3 square_to_uniform_sphere(Vec2 u);
inline constexpr float uniform_sphere_pdf() { return 0.25f * kInvPi; }
/// Uniform in the cone of directions around +z with cos(theta) >= cos_max; pdf 1/(2pi(1-cos_max)).
Vec3 square_to_uniform_cone(Vec2 u, float cos_max);
inline float uniform_cone_pdf(const Vec3& v, float cos_max) {
    return v.z >= cos_max ? 1.f / (2.f * kPi * (1.f - cos_max)) : 0.f;
}
/// Barycentric coordinates (b1, b2) uniform over a triangle. (Inline, as AliasTable::sample():
/// a light sample on a mesh takes both, and a call costs as much as either.)
inline Vec2 square_to_uniform_triangle(Vec2 u) {
    const float s = std::sqrt(u.x);
    return {1.f - s, u.y * s};
}

/// Sample an index of a discrete distribution given its normalized CDF (size n+1, cdf[0]=0,
/// cdf[n]=1). Returns the index and rescales `u` to [0,1) within the chosen interval.
uint32_t sample_discrete_cdf(const float* cdf, uint32_t n, float& u);

/// A discrete distribution sampled in O(1) by Walker's alias method (Vose's construction):
/// index i with probability weights[i] / sum(weights), whatever the number of entries (the
/// CDF search above takes log2 n steps and as many cache misses on a large mesh light).
class AliasTable {
public:
    AliasTable() = default;
    /// Weights >= 0 and finite, with a positive sum (else std::invalid_argument).
    explicit AliasTable(const std::vector<double>& weights);
    size_t size() const { return entries_.size(); }
    /// An index, with `u` rescaled to [0, 1) within the part of [0, 1) that chose it, for
    /// reuse. Never an index of weight 0. The table must not be empty.
    uint32_t sample(float& u) const {
        const uint32_t n = uint32_t(entries_.size());
        const double scaled = double(u) * double(n);
        const uint32_t i = std::min(uint32_t(scaled), n - 1);
        const float f = std::min(float(scaled - double(i)), 0x1.fffffep-1f);
        const Cell& c = entries_[i];
        // The rescalings multiply by stored reciprocals: a division is slow, and a light
        // sample's steps wait on each other.
        if (f < c.threshold) {
            u = std::min(f * c.inv_threshold, 0x1.fffffep-1f);
            return i;
        }
        u = std::min((f - c.threshold) * c.inv_rest, 0x1.fffffep-1f);
        return c.alias;
    }

private:
    // Cell i (of width 1/n) keeps i below `threshold` (a fraction of the cell) and gives
    // `alias` above it.
    struct Cell {
        float threshold = 1.f;
        uint32_t alias = 0;
        float inv_threshold = 1.f, inv_rest = 0.f;  // 1 / threshold, 1 / (1 - threshold)
    };
    std::vector<Cell> entries_;
};

}  // namespace femto::warp
