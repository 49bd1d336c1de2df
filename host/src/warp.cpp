#include "femto/warp.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace femto::warp {

Vec2 square_to_uniform_disk(Vec2 u) {
    const float a = 2.f * u.x - 1.f, b = 2.f * u.y - 1.f;
    if (a == 0 && b == 0) return {0, 0};
    float r, phi;
    if (a * a > b * b) {
        r = a;
        phi = (kPi / 4.f) * (b / a);
    } else {
        r = b;
        phi = (kPi / 2.f) - (kPi / 4.f) * (a / b);
    }
    return {r * std::cos(phi), r * std::sin(phi)};
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

Vec2 square_to_uniform_triangle(Vec2 u) {
    const float s = std::sqrt(u.x);
    return {1.f - s, u.y * s};
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

}  // namespace femto::warp
