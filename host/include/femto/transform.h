// femto public API: affine/projective 4x4 transforms in double precision.
#pragma once

#include <array>
#include <string>

#include "femto/math.h"

namespace femto {

/// A 4x4 matrix with its inverse, stored row-major and applied to column vectors
/// (p' = M p), as in Mitsuba's `matrix value="..."` (which lists rows).
class Transform {
public:
    using Matrix = std::array<std::array<double, 4>, 4>;

    Transform();  ///< identity
    /// Throws std::domain_error when `m` is singular (a degenerate transform).
    explicit Transform(const Matrix& m);
    Transform(const Matrix& m, const Matrix& inverse) : m_(m), inv_(inverse) {}

    static Transform translate(const Vec3& t);
    static Transform scale(const Vec3& s);
    /// Rotation by `angle_deg` degrees around `axis` (right-handed, as Mitsuba).
    static Transform rotate(const Vec3& axis, double angle_deg);
    /// Mitsuba's lookat: local +z looks at `target`, +y is as close to `up` as possible,
    /// +x = cross(up, dir) (the camera's left).
    static Transform look_at(const Vec3& origin, const Vec3& target, const Vec3& up);

    /// this * other: `other` is applied first.
    Transform operator*(const Transform& other) const;
    Transform inverse() const { return Transform(inv_, m_); }

    Vec3 point(const Vec3& p) const;   ///< applies translation and the projective divide
    Vec3 vector(const Vec3& v) const;  ///< ignores translation
    Vec3 normal(const Vec3& n) const;  ///< inverse transpose, not normalized
    const Matrix& matrix() const { return m_; }
    const Matrix& inverse_matrix() const { return inv_; }
    bool is_identity() const;
    /// Determinant of the upper-left 3x3 block (negative = handedness flip).
    double det3() const;

private:
    Matrix m_, inv_;
};

/// Largest coordinate magnitude, in scene units, of anything placed in the scene (mesh
/// vertices, sphere extents, sensor and emitter positions, after their transforms). Rays, hits
/// and areas are single precision: the squared length of a cross product of two edges (areas,
/// normals) overflows a float once edges pass ~4e9, which turns images black, and Embree
/// aborts on ray origins beyond ~1.8e18. Within +-1e9 every such product stays finite.
inline constexpr double kMaxSceneCoordinate = 1e9;
/// True when x, y and z are finite and within +-kMaxSceneCoordinate.
bool within_scene_range(double x, double y, double z);
inline bool within_scene_range(const Vec3& p) { return within_scene_range(p.x, p.y, p.z); }
/// An error message: `what` lies at (x, y, z), outside that range, and why that is refused.
std::string outside_scene_range(const std::string& what, double x, double y, double z);
inline std::string outside_scene_range(const std::string& what, const Vec3& p) {
    return outside_scene_range(what, p.x, p.y, p.z);
}

}  // namespace femto
