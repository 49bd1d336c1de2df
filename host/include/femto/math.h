// femto public API: small vector math used by every plugin.
//
// Geometry is single precision (it is what Embree traces); time is double (see femto/time.h
// and docs/units.md). Written by hand rather than taken from Imath so that plugin authors
// get a dependency-free, constexpr header with conventional operators (see docs/design-notes.md).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace femto {

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvPi = 0.31830988618379067154f;
inline constexpr float kInvTwoPi = 0.15915494309189533577f;
inline constexpr float kInfinity = std::numeric_limits<float>::infinity();
/// How far a ray leaving a surface starts off it, as a fraction of the magnitude of the
/// coordinates its hit point was computed from (Hit::p_error; docs/precision.md): 64 float
/// ulps, a few times the rounding of the hit point and of Embree's intersection test, and
/// scale-free, so a scene behaves the same at every size.
inline constexpr float kRayOffsetScale = 64.f * std::numeric_limits<float>::epsilon() / 2.f;

struct Vec2 {
    float x = 0, y = 0;
    constexpr Vec2() = default;
    constexpr Vec2(float x_, float y_) : x(x_), y(y_) {}
    constexpr Vec2 operator+(Vec2 b) const { return {x + b.x, y + b.y}; }
    constexpr Vec2 operator-(Vec2 b) const { return {x - b.x, y - b.y}; }
    constexpr Vec2 operator*(float s) const { return {x * s, y * s}; }
};

struct Vec3 {
    float x = 0, y = 0, z = 0;
    constexpr Vec3() = default;
    constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
    constexpr explicit Vec3(float s) : x(s), y(s), z(s) {}
    constexpr float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr Vec3 operator+(const Vec3& b) const { return {x + b.x, y + b.y, z + b.z}; }
    constexpr Vec3 operator-(const Vec3& b) const { return {x - b.x, y - b.y, z - b.z}; }
    constexpr Vec3 operator-() const { return {-x, -y, -z}; }
    constexpr Vec3 operator*(float s) const { return {x * s, y * s, z * s}; }
    constexpr Vec3 operator/(float s) const { return {x / s, y / s, z / s}; }
    constexpr Vec3 operator*(const Vec3& b) const { return {x * b.x, y * b.y, z * b.z}; }
    constexpr Vec3& operator+=(const Vec3& b) {
        x += b.x;
        y += b.y;
        z += b.z;
        return *this;
    }
    constexpr Vec3& operator-=(const Vec3& b) {
        x -= b.x;
        y -= b.y;
        z -= b.z;
        return *this;
    }
    constexpr Vec3& operator*=(float s) {
        x *= s;
        y *= s;
        z *= s;
        return *this;
    }
    constexpr bool operator==(const Vec3& b) const { return x == b.x && y == b.y && z == b.z; }
};
constexpr Vec3 operator*(float s, const Vec3& v) { return v * s; }
constexpr float dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length(const Vec3& v) { return std::sqrt(dot(v, v)); }
constexpr float squared_length(const Vec3& v) { return dot(v, v); }
inline Vec3 normalize(const Vec3& v) { return v / length(v); }
inline bool is_finite(const Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
inline float max_abs_component(const Vec3& v) {
    return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
}
/// Reflect `w` about `n` (both pointing away from the surface).
constexpr Vec3 reflect(const Vec3& w, const Vec3& n) { return 2.f * dot(w, n) * n - w; }

/// An orthonormal frame; local z is the normal. Building it follows Duff et al. 2017.
struct Frame {
    Vec3 s{1, 0, 0}, t{0, 1, 0}, n{0, 0, 1};
    Frame() = default;
    explicit Frame(const Vec3& normal) : n(normal) {
        const float sign = std::copysign(1.0f, n.z);
        const float a = -1.0f / (sign + n.z);
        const float b = n.x * n.y * a;
        s = {1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x};
        t = {b, sign + n.y * n.y * a, -n.y};
    }
    Vec3 to_local(const Vec3& v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    Vec3 to_world(const Vec3& v) const { return s * v.x + t * v.y + n * v.z; }
};

/// Trigonometry of a direction given in a local shading frame (z = normal).
namespace local {
inline float cos_theta(const Vec3& w) { return w.z; }
inline float abs_cos_theta(const Vec3& w) { return std::abs(w.z); }
inline float sin2_theta(const Vec3& w) { return std::max(0.f, 1.f - w.z * w.z); }
inline float tan2_theta(const Vec3& w) { return sin2_theta(w) / (w.z * w.z); }
}  // namespace local

/// The rays through the neighbouring film positions (pos + (1, 0) and pos + (0, 1) pixels) of a
/// camera ray: their origins and directions (pbrt's ray differentials).
struct RayDifferential {
    Vec3 dx_o, dx_d, dy_o, dy_d;
    /// From the ray's film position to the centre of the pixel it was taken for, in pixels
    /// (set by the renderer; 0 for a ray through the centre): a prefiltering material centres
    /// its filter on the pixel, the area a box-filtered pixel averages, not on the sample.
    Vec2 to_pixel_centre{0.f, 0.f};
};

struct Ray {
    Vec3 o, d;
    float tmin = 0.f;
    float tmax = kInfinity;
    /// The camera ray's neighbours one pixel over (Sensor::sample_differential()), for the
    /// pixel footprint of its first hit (Hit::footprint). Only the renderer sets it, on camera
    /// rays, and it points to its stack: rays spawned from hits leave it null, and a ray kept
    /// beyond Integrator::sample() must not use it.
    const RayDifferential* differential = nullptr;
    Vec3 at(float t) const { return o + d * t; }
};

/// Origin offset by `offset` along the geometric normal, to the side `dir` leaves on, so a
/// ray leaving a surface does not re-hit it (offset: Hit::p_error).
inline Vec3 offset_origin(const Vec3& p, const Vec3& ng, const Vec3& dir, float offset) {
    return p + ng * (dot(ng, dir) >= 0 ? offset : -offset);
}

/// Length of a shadow ray toward a light point `target` at distance `dist`: short of it by
/// 1e-4 of the distance and by the point's own offset scale, so that it does not hit the
/// surface the point lies on.
inline float shadow_ray_length(float dist, const Vec3& target) {
    return std::max(0.f, dist * (1.f - 1e-4f) - kRayOffsetScale * max_abs_component(target));
}

/// |b - a| in double: path lengths (time) are measured between the actual vertices.
inline double distance_between(const Vec3& a, const Vec3& b) {
    const double x = double(b.x) - a.x, y = double(b.y) - a.y, z = double(b.z) - a.z;
    return std::sqrt(x * x + y * y + z * z);
}

template <typename T>
constexpr T clamp(T v, T lo, T hi) {
    return std::min(std::max(v, lo), hi);
}
inline float safe_sqrt(float v) { return std::sqrt(std::max(0.f, v)); }
inline float radians(float deg) { return deg * (kPi / 180.f); }

}  // namespace femto
