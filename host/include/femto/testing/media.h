// femto testing kit: closed forms for participating media (installed with the SDK, target
// femto::testing; needs GoogleTest): a homogeneous fog and the exact single-scattering term
// along a camera ray, binned in time, and the per-bin comparison against a rendered cube.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "femto/testing/render.h"

namespace femto::testing {

constexpr double kPi64 = 3.14159265358979323846;

/// A point or direction in double precision.
struct Point3 {
    double x, y, z;
};

/// A homogeneous medium with id "fog" (Henyey-Greenstein phase g; isotropic at 0).
struct Fog {
    double sigma_a = 0.1, sigma_s = 0.5, eta = 1.0, g = 0.0;
    double sigma_t() const { return sigma_a + sigma_s; }
    std::string xml() const {
        std::ostringstream s;
        s << "<medium type=\"homogeneous\" id=\"fog\"><float name=\"sigma_a\" value=\"" << sigma_a
          << "\"/><float name=\"sigma_s\" value=\"" << sigma_s << "\"/><float name=\"eta\" value=\""
          << eta << "\"/>";
        if (g != 0) s << "<phase type=\"hg\"><float name=\"g\" value=\"" << g << "\"/></phase>";
        s << "</medium>";
        return s.str();
    }
    double phase(double cos_theta) const {  // cos_theta between propagation directions
        if (g == 0) return 1.0 / (4 * kPi64);
        const double denom = 1 + g * g - 2 * g * cos_theta;
        return (1 - g * g) / (4 * kPi64 * denom * std::sqrt(denom));
    }
};

/// Single scattering along the camera ray o + s d, s in [s0, s1), toward a point light of
/// `intensity` at `light`, binned by time [start + i width, ...), i < bins:
///   L(t) = integral ds sigma_s p(d . w_l) I e^(-sigma_t (s + r(s))) / r(s)^2
///                      delta(t - eta (s + r(s)))
/// with r(s) the distance from x(s) to the light and w_l its direction, by the midpoint rule
/// on 4e5 steps (relative error < 1e-6 for the windows the tests use).
inline std::vector<double> single_scattering(const Fog& fog, const Point3& o, const Point3& d,
                                             const Point3& light, double intensity, double s0,
                                             double s1, double start, double width, int bins) {
    std::vector<double> out(size_t(bins), 0.0);
    constexpr int kSteps = 400000;
    const double h = (s1 - s0) / kSteps;
    for (int i = 0; i < kSteps; ++i) {
        const double s = s0 + (i + 0.5) * h;
        const Point3 x{o.x + s * d.x, o.y + s * d.y, o.z + s * d.z};
        const Point3 to{light.x - x.x, light.y - x.y, light.z - x.z};
        const double r = std::sqrt(to.x * to.x + to.y * to.y + to.z * to.z);
        // Light travels along -to/r toward x, then along -d toward the camera.
        const double cos_theta = (to.x * d.x + to.y * d.y + to.z * d.z) / r;
        const double value = fog.sigma_s * fog.phase(cos_theta) * intensity *
                             std::exp(-fog.sigma_t() * (s + r)) / (r * r);
        const double t = fog.eta * (s + r);
        const int b = int(std::floor((t - start) / width));
        if (b >= 0 && b < bins) out[size_t(b)] += value * h;
    }
    return out;
}

/// Adds `value` spread uniformly over [t - half_width, t + half_width) to the bins
/// [start + i width, ...) of `out`: each bin gets its overlap (a box time kernel, integrated
/// over the bins exactly).
inline void add_box_in_time(std::vector<double>& out, double value, double t, double half_width,
                            double start, double width) {
    const double lo = t - half_width, hi = t + half_width;
    const int bins = int(out.size());
    const int first = std::max(0, int(std::floor((lo - start) / width)));
    const int last = std::min(bins - 1, int(std::floor((hi - start) / width)));
    for (int b = first; b <= last; ++b) {
        const double a = std::max(lo, start + b * width);
        const double e = std::min(hi, start + (b + 1) * width);
        if (e > a) out[size_t(b)] += value * (e - a) / (hi - lo);
    }
}

/// single_scattering() as a volumetric density estimate with box kernels sees it (photon
/// mapping): the light scattered at x is counted by every camera point within `radius` of x,
/// so each camera point sees the average over the ball of radius `radius` around it, and each
/// arrival is spread uniformly over +-half_width in time. Midpoint rule on `steps` points
/// along the ray times a grid of 16^3 cells over the ball (those whose centres lie in it);
/// the time spread is integrated over the bins exactly.
inline std::vector<double> single_scattering_smoothed(const Fog& fog, const Point3& o,
                                                      const Point3& d, const Point3& light,
                                                      double intensity, double s0, double s1,
                                                      double start, double width, int bins,
                                                      double radius, double half_width,
                                                      int steps = 4000) {
    std::vector<Point3> ball;
    constexpr int kCells = 16;
    for (int k = 0; k < kCells; ++k)
        for (int j = 0; j < kCells; ++j)
            for (int i = 0; i < kCells; ++i) {
                const Point3 u{(2 * (i + 0.5) / kCells - 1) * radius,
                               (2 * (j + 0.5) / kCells - 1) * radius,
                               (2 * (k + 0.5) / kCells - 1) * radius};
                if (u.x * u.x + u.y * u.y + u.z * u.z < radius * radius) ball.push_back(u);
            }
    std::vector<double> out(size_t(bins), 0.0);
    const double h = (s1 - s0) / steps, per_point = 1.0 / double(ball.size());
    for (int n = 0; n < steps; ++n) {
        const double s = s0 + (n + 0.5) * h, camera = std::exp(-fog.sigma_t() * s) * h;
        for (const Point3& u : ball) {
            const Point3 x{o.x + s * d.x + u.x, o.y + s * d.y + u.y, o.z + s * d.z + u.z};
            const Point3 to{light.x - x.x, light.y - x.y, light.z - x.z};
            const double r = std::sqrt(to.x * to.x + to.y * to.y + to.z * to.z);
            const double cos_theta = (to.x * d.x + to.y * d.y + to.z * d.z) / r;
            const double value = camera * per_point * fog.sigma_s * fog.phase(cos_theta) *
                                 intensity * std::exp(-fog.sigma_t() * r) / (r * r);
            add_box_in_time(out, value, fog.eta * (s + r), half_width, start, width);
        }
    }
    return out;
}

/// single_scattering() as photon beams with a box blur of radius `radius` across each beam see
/// it (beam x beam, 1D blur): a beam from the light in direction w counts at the camera ray's
/// point x(s) closest to its line when the lines pass within `radius`, with weight
/// 1 / (2 radius sin(d, w)). Parameterising the beams by that point s and the signed distance u
/// between the lines, the beam's closest point is y = x(s) + u n, with n the unit vector
/// normal to d and to y - light, and the expectation is
///   integral ds du / (2 radius) J(s, u) I Tr(|y - light|) sigma_s p Tr(s) / sin(d, w)
/// with J the solid angle of beam directions per unit s and u (by central differences), timed
/// eta (s + |y - light|) and spread uniformly over +-half_width. Midpoint rule on `steps` x 64
/// points; needs radius below the light's distance from the camera line.
inline std::vector<double> single_scattering_beams(const Fog& fog, const Point3& o, const Point3& d,
                                                   const Point3& light, double intensity, double s0,
                                                   double s1, double start, double width, int bins,
                                                   double radius, double half_width,
                                                   int steps = 4000) {
    struct V {
        double x, y, z;
        V operator+(V b) const { return {x + b.x, y + b.y, z + b.z}; }
        V operator-(V b) const { return {x - b.x, y - b.y, z - b.z}; }
        V operator*(double k) const { return {x * k, y * k, z * k}; }
        double dot(V b) const { return x * b.x + y * b.y + z * b.z; }
        V cross(V b) const { return {y * b.z - z * b.y, z * b.x - x * b.z, x * b.y - y * b.x}; }
        double norm() const { return std::sqrt(dot(*this)); }
    };
    const V D{d.x, d.y, d.z}, O{o.x, o.y, o.z}, L{light.x, light.y, light.z};
    // The beam's closest point for (s, u).
    auto closest = [&](double s, double u) {
        const V x = O + D * s, a = L - x, perp = a - D * a.dot(D);
        const double rho = perp.norm();
        const V e1 = perp * (1 / rho), e2 = D.cross(e1);
        const double c = u / rho;
        return x + (e1 * c + e2 * std::sqrt(1 - c * c)) * u;
    };
    auto direction = [&](double s, double u) {
        const V w = closest(s, u) - L;
        return w * (1 / w.norm());
    };
    constexpr int kAcross = 64;
    std::vector<double> out(size_t(bins), 0.0);
    const double h = (s1 - s0) / steps, du = 2 * radius / kAcross;
    const double eps = 1e-5 * radius;
    for (int n = 0; n < steps; ++n) {
        const double s = s0 + (n + 0.5) * h;
        for (int k = 0; k < kAcross; ++k) {
            const double u = -radius + (k + 0.5) * du;
            const V y = closest(s, u), w = (y - L) * (1 / (y - L).norm());
            const double r = (y - L).norm();
            const V ws = (direction(s + eps, u) - direction(s - eps, u)) * (1 / (2 * eps));
            const V wu = (direction(s, u + eps) - direction(s, u - eps)) * (1 / (2 * eps));
            const double J = ws.cross(wu).norm(), sin_dw = D.cross(w).norm();
            // Light travels along w, then along -d toward the camera.
            const double value = h * du / (2 * radius) * J * intensity *
                                 std::exp(-fog.sigma_t() * (r + s)) * fog.sigma_s *
                                 fog.phase(-w.dot(D)) / sin_dw;
            add_box_in_time(out, value, fog.eta * (s + r), half_width, start, width);
        }
    }
    return out;
}

/// Expects every bin of pixel (0, 0), channel 0 (the media are grey), to match `expected`
/// within 4 standard errors (from the film's variance AOV) + `relative` x the expected value
/// (the quadrature's error); returns the number of bins that carry signal.
inline int expect_bins(const Cube& cube, const Cube& variance, const std::vector<double>& expected,
                       double relative = 1e-4) {
    int signal = 0, bad = 0;
    for (int t = 0; t < cube.T; ++t) {
        const double got = cube.at(0, 0, t, 0), se = std::sqrt(double(variance.at(0, 0, t, 0)));
        const double want = expected[size_t(t)];
        if (want > 0) ++signal;
        if (std::abs(got - want) > 4 * se + relative * std::abs(want) + 1e-12 && ++bad <= 10)
            ADD_FAILURE() << "bin " << t << ": rendered " << got << " +- " << se << ", expected "
                          << want;
    }
    EXPECT_EQ(bad, 0);
    return signal;
}

}  // namespace femto::testing
