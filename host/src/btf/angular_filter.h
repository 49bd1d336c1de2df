// Filtering a BTF over light and view solid angles (Jarabo, Plenoptic Light Transport, ch. 3:
// each level of the prefiltered hierarchy holds versions of the BTF averaged over cones of
// directions of half-angle 0, 15, 30, 45 degrees) as linear operators on the sampled directions.
//
// A function sampled at the n directions is fitted with real spherical harmonics up to
// `degree` (regularized least squares, as the samples cover only the upper hemisphere), and a
// radial kernel of half-angle alpha scales band l by its Funk-Hecke coefficient lambda_l(alpha):
// for the box (the mean over the cap) lambda_l = (P_{l-1}(cos a) - P_{l+1}(cos a)) /
// ((2l + 1)(1 - cos a)), so lambda_1 = (1 + cos a)/2 and lambda_2 = cos a (1 + cos a)/2; for
// the Gaussian and Lanczos kernels (pbrt's shapes, over the angle from the cap's centre) it is
// integrated numerically. What the fit leaves out (the samples' residual: highlights, shadow
// edges) is averaged directly: the interpolated residual (DirectionMesh, barycentric between
// the samples) integrated over the cone by a quadrature Q of rings x azimuths. So the filter is
// the n x n matrix
//   F(alpha) = Y Lambda(alpha) Y+ + Q(alpha) (I - Y Y+),
// which is exactly the identity at alpha = 0 and exact for any function of bands <= degree
// (such as the synthetic BTF A of btf/synth.h). The fit has a low degree (2 by default): the
// samples cover the hemisphere up to 75 degrees only, and the normal matrix of a degree-4 fit
// has a condition number of ~1e7 (degree 2: ~1e3). Being linear, the filter acts on a
// factorized BTF through its angular factors only.
#pragma once

#include <cstdint>
#include <vector>

#include "femto/btf_prefilter.h"
#include "femto/math.h"

namespace femto::btf {

inline constexpr double kPiD = 3.14159265358979323846;

/// Number of real spherical harmonics up to `degree`: (degree + 1)^2.
inline int sh_count(int degree) { return (degree + 1) * (degree + 1); }
/// The real spherical harmonics Y_lm(d) up to `degree` (orthonormal on the sphere), at index
/// l (l + 1) + m.
void sh_eval(int degree, const Vec3& d, double* out);

/// The angular filter on one set of sampled directions.
class AngularFilter {
public:
    /// `regularization` weighs a smoothness penalty l^2 (l + 1)^2 on the coefficients, which
    /// keeps the fit's extrapolation below the horizon tame.
    AngularFilter(const std::vector<Vec3>& directions, int degree, double regularization = 1e-10);
    size_t size() const { return n_; }
    int degree() const { return degree_; }
    /// F(alpha), n x n, row-major: filtered values = F * sampled values.
    std::vector<double> matrix(FilterKernel kernel, double alpha) const;

private:
    /// Q(alpha): the kernel-weighted mean over the cone around each sample of the interpolated
    /// values, as an n x n matrix (the identity at alpha = 0).
    std::vector<double> cone_quadrature(FilterKernel kernel, double alpha) const;

    std::vector<Vec3> directions_;
    DirectionMesh mesh_;  // interpolates the residual inside the cones
    size_t n_;
    int degree_;
    std::vector<double> basis_;    // n x count: Y
    std::vector<double> inverse_;  // count x n: the regularized pseudo-inverse Y+
};

}  // namespace femto::btf
