// `femto bench`: error measures of a render against its reference, and the statistics of a
// convergence study (docs/bench.md gives every formula).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace femto::bench {

/// A render as a cube [H, W, T, C] (a steady image is T = 1), and its time grid (the centre
/// of bin t is start + (t + 0.5) * bin_width; unused when T = 1).
struct Cube {
    size_t H = 0, W = 0, T = 0, C = 0;
    std::vector<float> data;
    /// For a reference: the variance of each voxel's estimate, or empty when unknown. The
    /// measures then subtract it: for a render x independent of the reference r,
    /// E sum (x - r)^2 = sum E (x - truth)^2 + sum Var r, so what remains is x's own error.
    std::vector<float> variance;
    double start = 0, bin_width = 0;
    size_t size() const { return H * W * T * C; }
};

/// relMSE = sum_v ((x_v - r_v)^2 - Var r_v) / sum_v r_v^2 over the voxels v (pixel, bin,
/// channel) whose bin centre lies in [t0, t1): the squared relative L2 error of that part of
/// the cube against the truth (Var r = 0 when the reference's variance is unknown; with it, a
/// render as good as the reference may come out slightly negative). NaN when the reference is
/// black there. Every measure below subtracts Var r the same way.
double rel_mse(const Cube& x, const Cube& ref, double t0, double t1);
/// rel_mse over the whole cube.
double rel_mse(const Cube& x, const Cube& ref);
/// Mean over the pixels that the reference lights in [t0, t1) of each pixel's own relMSE over
/// that window: every lit pixel weighs the same, however bright.
double pixel_rel_mse(const Cube& x, const Cube& ref, double t0, double t1);
/// The relMSE of pixel (px, py)'s time profile (its bins and channels); throws
/// std::runtime_error when the pixel is outside the film.
double pixel_profile_rel_mse(const Cube& x, const Cube& ref, int px, int py);
/// Pixel (px, py)'s time profile: the mean over channels of each bin.
std::vector<double> pixel_profile(const Cube& x, int px, int py);
/// relMSE of each frame (bin) t, NaN where the reference frame is black.
std::vector<double> frame_rel_mse(const Cube& x, const Cube& ref);
/// The mean of frame_rel_mse over the frames the reference resolves: lit, and (when its
/// variance is known) with its own noise sum_v Var r_v / sum_v r_v^2 below 5 %. Every resolved
/// frame weighs the same, the late dim ones as much as the first light (the thesis' error over
/// frames); the whole cube's relMSE is dominated by the brightest frames instead. NaN when no
/// frame is resolved.
double resolved_frame_rel_mse(const Cube& x, const Cube& ref);
/// (sum x - sum r) / sum r: the relative error of the total energy.
double energy_error(const Cube& x, const Cube& ref);
/// `c` with its variance dropped (the measures then compare against r as it is).
Cube without_variance(Cube c);
/// Throws std::runtime_error when the two cubes' shapes differ.
void check_same_shape(const Cube& x, const Cube& ref);

/// Least squares of log(error) = a + b log(seconds) over runs with positive error and time:
/// `slope` b with the half-width of its 95 % confidence interval (Student t, n - 2 degrees of
/// freedom). The slope is NaN with fewer than 2 runs, the interval with fewer than 3. `n`
/// counts the runs fitted: runs whose error is not positive (possible once the reference's
/// variance is taken out) are left out, which flattens the slope when they are many.
struct Fit {
    double slope = 0, intercept = 0, slope_ci95 = 0;
    int n = 0;
    double seconds_at(double error) const;  ///< the fitted time to reach `error`
};
Fit fit_log_log(const std::vector<double>& seconds, const std::vector<double>& errors);

/// Equal-error time ratio of B over A (or of any other cost, e.g. samples, in place of
/// seconds): the fitted time B needs to reach the geometric mean of
/// A's errors over the fitted time A needs for it (< 1: B is faster). The 95 % interval comes
/// from 2000 bootstrap resamples of each variant's runs (a fixed seed: reports reproduce); NaN
/// bounds when more than 5 % of the resamples give no ratio.
struct Ratio {
    double value = 0, lo = 0, hi = 0;
};
Ratio equal_error_ratio(const std::vector<double>& seconds_a, const std::vector<double>& errors_a,
                        const std::vector<double>& seconds_b, const std::vector<double>& errors_b);

/// The median of b_i / a_i over pairs run side by side (the same budget and seed, one after the
/// other: a drift of the machine's speed cancels), with a 95 % interval from 2000 bootstrap
/// resamples of the pairs (fixed seed). NaN bounds with fewer than 3 pairs.
Ratio paired_median_ratio(const std::vector<double>& a, const std::vector<double>& b);
/// The median (NaN when empty).
double median(std::vector<double> v);

/// This process's CPU time so far (user + system, every thread), in seconds: over a run's wall
/// clock, the cores it actually used.
double process_cpu_seconds();

/// The 97.5 % quantile of Student's t with `dof` degrees of freedom (a two-sided 95 % interval).
double student_t975(int dof);

}  // namespace femto::bench
