#include "femto/transform.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <stdexcept>

namespace femto {

namespace {
using Matrix = Transform::Matrix;

Matrix identity() {
    Matrix m{};
    for (int i = 0; i < 4; ++i) m[i][i] = 1.0;
    return m;
}

Matrix multiply(const Matrix& a, const Matrix& b) {
    Matrix r{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += a[i][k] * b[k][j];
            r[i][j] = s;
        }
    return r;
}

// Gauss-Jordan with partial pivoting; singular (relative to the matrix scale) -> throw.
Matrix invert(const Matrix& m) {
    Matrix a = m, inv = identity();
    double scale = 0;
    for (const auto& row : m)
        for (double v : row) scale = std::max(scale, std::abs(v));
    if (!(scale > 0) || !std::isfinite(scale))
        throw std::domain_error("matrix is zero or not finite");
    for (int c = 0; c < 4; ++c) {
        int pivot = c;
        for (int r = c + 1; r < 4; ++r)
            if (std::abs(a[r][c]) > std::abs(a[pivot][c])) pivot = r;
        if (std::abs(a[pivot][c]) < 1e-12 * scale) throw std::domain_error("matrix is singular");
        std::swap(a[c], a[pivot]);
        std::swap(inv[c], inv[pivot]);
        const double d = 1.0 / a[c][c];
        for (int j = 0; j < 4; ++j) {
            a[c][j] *= d;
            inv[c][j] *= d;
        }
        for (int r = 0; r < 4; ++r)
            if (r != c) {
                const double f = a[r][c];
                if (f == 0) continue;
                for (int j = 0; j < 4; ++j) {
                    a[r][j] -= f * a[c][j];
                    inv[r][j] -= f * inv[c][j];
                }
            }
    }
    return inv;
}
}  // namespace

Transform::Transform() : m_(identity()), inv_(identity()) {}
Transform::Transform(const Matrix& m) : m_(m), inv_(invert(m)) {}

Transform Transform::translate(const Vec3& t) {
    Matrix m = identity(), inv = identity();
    for (int i = 0; i < 3; ++i) {
        m[i][3] = t[i];
        inv[i][3] = -t[i];
    }
    return Transform(m, inv);
}

Transform Transform::scale(const Vec3& s) {
    Matrix m = identity();
    for (int i = 0; i < 3; ++i) m[i][i] = s[i];
    return Transform(m);  // inverts (and rejects a zero scale)
}

Transform Transform::rotate(const Vec3& axis_in, double angle_deg) {
    const double len = std::sqrt(double(axis_in.x) * axis_in.x + double(axis_in.y) * axis_in.y +
                                 double(axis_in.z) * axis_in.z);
    if (!(len > 0)) throw std::domain_error("rotation axis is zero");
    const double x = axis_in.x / len, y = axis_in.y / len, z = axis_in.z / len;
    const double a = angle_deg * M_PI / 180.0, s = std::sin(a), c = std::cos(a), t = 1 - c;
    Matrix m = identity();
    m[0] = {t * x * x + c, t * x * y - s * z, t * x * z + s * y, 0};
    m[1] = {t * x * y + s * z, t * y * y + c, t * y * z - s * x, 0};
    m[2] = {t * x * z - s * y, t * y * z + s * x, t * z * z + c, 0};
    Matrix inv = identity();  // orthonormal: inverse = transpose
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) inv[i][j] = m[j][i];
    return Transform(m, inv);
}

// In double: squared lengths of float vectors neither overflow (an `up` of 1e30 was "parallel")
// nor underflow (an origin 1e-30 from its target "equalled" it).
Transform Transform::look_at(const Vec3& origin, const Vec3& target, const Vec3& up) {
    using D3 = std::array<double, 3>;
    const auto cross_d = [](const D3& a, const D3& b) -> D3 {
        return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    };
    const auto norm2 = [](const D3& a) { return a[0] * a[0] + a[1] * a[1] + a[2] * a[2]; };
    const auto unit = [&](const D3& a) -> D3 {
        const double len = std::sqrt(norm2(a));
        return {a[0] / len, a[1] / len, a[2] / len};
    };
    const D3 diff{double(target.x) - origin.x, double(target.y) - origin.y,
                  double(target.z) - origin.z};
    if (!(norm2(diff) > 0)) throw std::domain_error("lookat origin equals target");
    const D3 dir = unit(diff), up_d{up.x, up.y, up.z};
    if (!(norm2(up_d) > 0)) throw std::domain_error("lookat 'up' is zero");
    D3 left = cross_d(unit(up_d), dir);
    if (!(norm2(left) > 1e-12))
        throw std::domain_error("lookat 'up' is parallel to the viewing direction");
    left = unit(left);
    const D3 new_up = cross_d(dir, left);
    Matrix m = identity();
    for (int i = 0; i < 3; ++i) {
        m[i][0] = left[size_t(i)];
        m[i][1] = new_up[size_t(i)];
        m[i][2] = dir[size_t(i)];
        m[i][3] = origin[i];
    }
    return Transform(m);
}

Transform Transform::operator*(const Transform& o) const {
    return Transform(multiply(m_, o.m_), multiply(o.inv_, inv_));
}

Vec3 Transform::point(const Vec3& p) const {
    double r[4];
    for (int i = 0; i < 4; ++i) r[i] = m_[i][0] * p.x + m_[i][1] * p.y + m_[i][2] * p.z + m_[i][3];
    if (r[3] != 1.0 && r[3] != 0.0)
        for (int i = 0; i < 3; ++i) r[i] /= r[3];
    return {float(r[0]), float(r[1]), float(r[2])};
}

Vec3 Transform::vector(const Vec3& v) const {
    Vec3 r;
    for (int i = 0; i < 3; ++i) r[i] = float(m_[i][0] * v.x + m_[i][1] * v.y + m_[i][2] * v.z);
    return r;
}

Vec3 Transform::normal(const Vec3& n) const {
    Vec3 r;
    for (int i = 0; i < 3; ++i)
        r[i] = float(inv_[0][i] * n.x + inv_[1][i] * n.y + inv_[2][i] * n.z);
    return r;
}

bool Transform::is_identity() const { return m_ == identity(); }

double Transform::det3() const {
    const auto& m = m_;
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

bool within_scene_range(double x, double y, double z) {
    for (const double v : {x, y, z})
        if (!(std::abs(v) <= kMaxSceneCoordinate)) return false;  // also false for NaN
    return true;
}

std::string outside_scene_range(const std::string& what, double x, double y, double z) {
    return fmt::format(
        "{} lies at ({:g}, {:g}, {:g}), beyond femto's limit of +-{:g} scene units: rays and "
        "areas are computed in single precision, which overflows past it (black images, or a "
        "crash); scale the scene down (e.g. use a larger length unit)",
        what, x, y, z, kMaxSceneCoordinate);
}

}  // namespace femto
