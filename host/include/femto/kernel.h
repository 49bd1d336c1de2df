// femto public API: density-estimation kernels and their progressive bandwidth schedule, shared
// by the `kernel` temporal filter (thesis ch. 5.5, appendix 5.A) and the photon-density
// integrators (ch. 5.5.1, appendix 5.B): the kernel's shape, its exact integral over a film's
// time bins, its normalisation as a radial kernel in 1, 2 or 3 dimensions, and the shrinking
// factor of eq. 5.47 / 5.58.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "femto/properties.h"
#include "femto/time.h"

namespace femto {

/// A symmetric kernel on [-1, 1] (docs/temporal-reconstruction.md): box; Epanechnikov,
/// 3/4 (1 - u^2); Perlin's smootherstep falloff, 1 - (6x^5 - 15x^4 + 10x^3) with x = |u|; a
/// Gaussian of sigma 1/3 truncated at 3 sigma.
enum class KernelShape : uint8_t { Box, Epanechnikov, Perlin, Gaussian };

/// Reads a kernel shape parameter ("box", "epanechnikov", "perlin" or "gaussian"); a located
/// SceneError names the valid ones.
KernelShape read_kernel_shape(const Properties& props, const std::string& name,
                              const std::string& default_shape);
/// The name read_kernel_shape() reads for `shape`.
const char* kernel_shape_name(KernelShape shape);

/// The kernel's falloff at |u| (1 at 0, 0 from 1 on), not normalised.
double kernel_profile(KernelShape shape, double u);
/// Cumulative distribution of the normalised 1D kernel on [-1, 1] (0 below, 1 above).
double kernel_cdf(KernelShape shape, double u);
/// Integral of kernel_profile(|x|) over the unit ball of R^dims (dims 1, 2 or 3): the radial
/// kernel of radius R in dims dimensions is kernel_profile(|x| / R) / (this * R^dims).
double kernel_ball_integral(KernelShape shape, int dims);

/// A contribution's spread in time: the kernel a density estimate applies to it (half-width
/// `half_width`, scene units of optical length); 0 is a point in time.
struct TimeKernel {
    float half_width = 0.f;
    KernelShape shape = KernelShape::Box;
    bool spreads() const { return half_width > 0.f; }
};

/// The kernel of half-width `half_width` centred on `t`, integrated exactly over each bin of
/// `grid` it overlaps: add(bin, weight) in bin order. Returns the mass that fell inside the
/// window (1 when the whole kernel did).
template <typename Add>
double integrate_over_bins(const TimeGrid& grid, KernelShape shape, double t, double half_width,
                           Add&& add) {
    const double lo = std::max(t - half_width, grid.start);
    const double hi = std::min(t + half_width, grid.end());
    if (!(lo < hi)) return 0.0;
    const int first = std::max(0, int(std::floor((lo - grid.start) / grid.bin_width)));
    const int last = std::min(grid.bins - 1, int(std::floor((hi - grid.start) / grid.bin_width)));
    const double inv = 1.0 / half_width;
    const double start = kernel_cdf(shape, (lo - t) * inv);
    double below = start;
    for (int b = first; b <= last; ++b) {
        const double edge = std::min(hi, grid.start + double(b + 1) * grid.bin_width);
        const double upto = kernel_cdf(shape, (edge - t) * inv);
        if (upto > below) add(b, upto - below);
        below = upto;
    }
    return below - start;
}

/// The progressive shrinking factor after `iteration` iterations (0, 1, ...): the product
/// prod_{i=1}^{iteration} (i + alpha) / (i + 1) = Gamma(alpha + j) / (Gamma(alpha + 1) Gamma(j +
/// 1)) with j = iteration + 1 (eq. 5.47; eq. 5.58 raises it to beta_T for the temporal bandwidth
/// and beta_R for the squared radius).
double progressive_shrink(double alpha, uint64_t iteration);

/// The joint schedule of transient progressive photon mapping (eq. 5.58, 5.77-5.78): after
/// `iteration` iterations the spatial kernel's volume is R_1^d s^beta_R and the time bandwidth
/// T_1 s^beta_T, s = progressive_shrink(alpha, iteration), beta_R = 1 - beta_t, so that each
/// iteration scales the variance of the estimate, proportional to 1 / (R^d T), by
/// (j + 1) / (j + alpha). d = `dims` is 2 for photons on surfaces (the thesis' case, where
/// R^2 shrinks by s^beta_R) and 3 for photons in a medium (docs/photon-mapping.md).
struct ProgressiveBandwidths {
    double alpha = 4.0 / 7.0;
    double beta_t = 1.0 / 3.0;
    int dims = 2;
    double radius_squared(double initial_radius_squared, uint64_t iteration) const {
        return initial_radius_squared *
               std::pow(progressive_shrink(alpha, iteration), 2.0 * (1.0 - beta_t) / double(dims));
    }
    double time(double initial_bandwidth, uint64_t iteration) const {
        return initial_bandwidth * std::pow(progressive_shrink(alpha, iteration), beta_t);
    }
};

}  // namespace femto
