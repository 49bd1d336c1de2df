// A reusable chi-square goodness-of-fit harness for sampling routines (after Mitsuba's
// ChiSquareTest): histogram many samples over a 2D domain, integrate the claimed density over
// every bin to get the expected counts, pool sparse bins, and compute the chi-square statistic
// and its p-value (regularized incomplete gamma, implemented here).
//
// Plus small helpers shared by the BSDF tests (building a BSDF through the plugin host, the
// (cos theta, phi) parameterisation of the sphere).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "femto/bsdf.h"
#include "femto/host.h"
#include "femto/math.h"
#include "femto/properties.h"
#include "femto/random.h"

namespace femto_test {

inline constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------
// Special functions

/// Regularized upper incomplete gamma function Q(a, x) = Gamma(a, x) / Gamma(a), a > 0:
/// the power series of P = 1 - Q for x < a + 1, else the continued fraction of Q evaluated by
/// the modified Lentz method (Numerical Recipes, 6.2).
inline double gamma_q(double a, double x) {
    if (!(x > 0.0)) return 1.0;
    const double log_prefactor = -x + a * std::log(x) - std::lgamma(a);
    if (x < a + 1.0) {
        double ap = a, del = 1.0 / a, sum = del;
        for (int n = 0; n < 100000; ++n) {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if (std::abs(del) < std::abs(sum) * 1e-16) break;
        }
        return std::max(0.0, 1.0 - sum * std::exp(log_prefactor));
    }
    constexpr double kTiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
    for (int i = 1; i < 100000; ++i) {
        const double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (std::abs(d) < kTiny) d = kTiny;
        c = b + an / c;
        if (std::abs(c) < kTiny) c = kTiny;
        d = 1.0 / d;
        const double del = d * c;
        h *= del;
        if (std::abs(del - 1.0) < 1e-16) break;
    }
    return std::exp(log_prefactor) * h;
}

/// P(X > chi2) for X chi-square distributed with `dof` degrees of freedom.
inline double chi2_p_value(double chi2, int dof) {
    return dof > 0 ? gamma_q(0.5 * dof, 0.5 * chi2) : 1.0;
}

// ---------------------------------------------------------------------------------------------
// Numerical integration

/// Adaptive Simpson quadrature of f over [a, b]: each interval is split at least `min_depth`
/// times (so narrow features inside a bin are seen), and refined until the Richardson error
/// estimate |S2 - S1| / 15 falls below its share of `eps`, or `max_depth` is reached.
template <typename F>
double adaptive_simpson(const F& f, double a, double b, double eps, int min_depth = 2,
                        int max_depth = 14) {
    struct Rec {
        const F& f;
        int min_depth, max_depth;
        double run(double a, double b, double fa, double fm, double fb, double whole, double eps,
                   int depth) const {
            const double m = 0.5 * (a + b), lm = 0.5 * (a + m), rm = 0.5 * (m + b);
            const double flm = f(lm), frm = f(rm);
            const double left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
            const double right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
            const double delta = left + right - whole;
            if (depth >= max_depth || (depth >= min_depth && std::abs(delta) <= 15.0 * eps))
                return left + right + delta / 15.0;
            return run(a, m, fa, flm, fm, left, 0.5 * eps, depth + 1) +
                   run(m, b, fm, frm, fb, right, 0.5 * eps, depth + 1);
        }
    };
    const Rec rec{f, min_depth, max_depth};
    const double fa = f(a), fb = f(b), fm = f(0.5 * (a + b));
    return rec.run(a, b, fa, fm, fb, (b - a) / 6.0 * (fa + 4.0 * fm + fb), eps, 0);
}

/// Integral of f(x, y) over [x0, x1] x [y0, y1] by nested adaptive Simpson quadrature, to
/// an absolute tolerance max(abs_eps, rel_eps * |I|) where |I| is first estimated by a 5 x 5
/// point Simpson rule. The inner integrals are computed 100x more accurately than their share
/// of the outer tolerance, so that their error does not look like structure to the outer rule.
template <typename F>
double integrate_2d(const F& f, double x0, double x1, double y0, double y1, double abs_eps,
                    double rel_eps = 0.0) {
    double coarse = 0.0;
    for (int i = 0; i <= 4; ++i)
        for (int j = 0; j <= 4; ++j) {
            const double wi = (i == 0 || i == 4) ? 1 : (i % 2 ? 4 : 2);
            const double wj = (j == 0 || j == 4) ? 1 : (j % 2 ? 4 : 2);
            coarse += wi * wj * f(x0 + 0.25 * i * (x1 - x0), y0 + 0.25 * j * (y1 - y0));
        }
    coarse *= (x1 - x0) * (y1 - y0) / 144.0;
    const double eps = std::max(abs_eps, rel_eps * std::abs(coarse));
    const double inner_eps = 1e-2 * eps / (x1 - x0);
    auto inner = [&](double x) {
        return adaptive_simpson([&](double y) { return f(x, y); }, y0, y1, inner_eps, 2, 12);
    };
    return adaptive_simpson(inner, x0, x1, eps, 2, 14);
}

// ---------------------------------------------------------------------------------------------
// The chi-square test

struct Chi2Options {
    int nx = 64, ny = 128;  ///< bins along x and y
    double x0 = -1, x1 = 1, y0 = 0, y1 = 2 * kPi;
    size_t samples = 1000000;
    uint64_t seed = 1;
    double min_expected = 5.0;  ///< bins expecting fewer samples are pooled
    /// Quadrature tolerance per bin: max(abs, rel * bin mass). A bin of mass m has a Poisson
    /// standard deviation of sqrt(N m) counts, i.e. sqrt(m / N) in mass; the defaults stay
    /// below 1% of it for every m >= 5 / N (expected counts below 5 are pooled anyway).
    double integration_abs_eps = 1e-9;
    double integration_rel_eps = 1e-5;
    /// Samples this close outside the domain (float rounding) count in the nearest bin.
    double edge_tolerance = 1e-5;
};

struct Chi2Result {
    double chi2 = 0, p_value = 0;
    int dof = 0;
    int pooled_bins = 0;
    double pdf_integral = 0;  ///< integral of the density over the whole domain
    size_t samples = 0;       ///< samples drawn
    size_t histogrammed = 0;  ///< samples the sampler returned (others failed or were rejected)
    size_t outside = 0;       ///< returned samples outside the domain
    size_t in_zero_bins = 0;  ///< samples in bins where the density integrates to zero
    std::string error;        ///< set when the test cannot be valid (e.g. non-finite density)

    double returned_fraction() const { return samples ? double(histogrammed) / samples : 0.0; }
    std::string describe() const {
        std::ostringstream os;
        os << "chi2 = " << chi2 << ", dof = " << dof << ", p = " << p_value
           << ", pooled bins = " << pooled_bins << ", pdf integral = " << pdf_integral
           << ", returned " << histogrammed << " / " << samples << " samples, outside = " << outside
           << ", in zero-density bins = " << in_zero_bins;
        if (!error.empty()) os << ", error: " << error;
        return os.str();
    }
};

/// Runs the test. `sample(Pcg32&)` returns the sampled point of the domain, or nullopt when
/// it produced no sample (a failed sample, or one the test conditions away). `pdf(x, y)` is
/// the density of returned samples with respect to dx dy; its integral may be below one by
/// the probability of returning nothing.
template <typename Sample, typename Pdf>
Chi2Result chi2_test(const Chi2Options& o, const Sample& sample, const Pdf& pdf) {
    Chi2Result res;
    const int nbins = o.nx * o.ny;
    const double wx = (o.x1 - o.x0) / o.nx, wy = (o.y1 - o.y0) / o.ny;
    const double tol_x = o.edge_tolerance * (o.x1 - o.x0), tol_y = o.edge_tolerance * (o.y1 - o.y0);

    std::vector<double> observed(nbins, 0.0), expected(nbins, 0.0);
    femto::Pcg32 rng(o.seed, 0x9e3779b97f4a7c15ULL);
    for (size_t i = 0; i < o.samples; ++i) {
        const std::optional<std::pair<double, double>> p = sample(rng);
        if (!p) continue;
        ++res.histogrammed;
        const double x = p->first, y = p->second;
        if (!(x >= o.x0 - tol_x && x <= o.x1 + tol_x && y >= o.y0 - tol_y && y <= o.y1 + tol_y)) {
            ++res.outside;
            continue;
        }
        const int ix = std::clamp(static_cast<int>(std::floor((x - o.x0) / wx)), 0, o.nx - 1);
        const int iy = std::clamp(static_cast<int>(std::floor((y - o.y0) / wy)), 0, o.ny - 1);
        observed[ix * o.ny + iy] += 1.0;
    }
    res.samples = o.samples;

    bool finite = true;
    auto density = [&](double x, double y) {
        const double v = pdf(x, y);
        if (!std::isfinite(v) || v < 0) {
            finite = false;
            return 0.0;
        }
        return v;
    };
    for (int ix = 0; ix < o.nx; ++ix)
        for (int iy = 0; iy < o.ny; ++iy) {
            const double xa = o.x0 + ix * wx, ya = o.y0 + iy * wy;
            const double mass = integrate_2d(density, xa, xa + wx, ya, ya + wy,
                                             o.integration_abs_eps, o.integration_rel_eps);
            res.pdf_integral += mass;
            expected[ix * o.ny + iy] = mass * static_cast<double>(o.samples);
        }
    if (!finite) res.error = "the density is negative or not finite somewhere";

    // Pool as Mitsuba does: visit bins by increasing expected count; bins below
    // min_expected (and following ones until the pool reaches it) are merged into one cell.
    std::vector<int> order(nbins);
    for (int i = 0; i < nbins; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](int a, int b) { return expected[a] < expected[b]; });
    double pooled_obs = 0, pooled_exp = 0;
    for (int idx : order) {
        const double e = expected[idx], n = observed[idx];
        if (e <= 0.0) {
            res.in_zero_bins += static_cast<size_t>(n);
            continue;
        }
        if (e < o.min_expected || (pooled_exp > 0 && pooled_exp < o.min_expected)) {
            pooled_obs += n;
            pooled_exp += e;
            ++res.pooled_bins;
        } else {
            res.chi2 += (n - e) * (n - e) / e;
            ++res.dof;
        }
    }
    if (pooled_exp > 0) {
        res.chi2 += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / pooled_exp;
        ++res.dof;
    }
    res.dof -= 1;  // the counts are constrained by their total
    // Samples where the density is zero cannot be explained by any chi2 value; Mitsuba
    // tolerates a fraction 1e-5 of the samples there (rounding at domain edges).
    if (res.in_zero_bins > static_cast<size_t>(1e-5 * o.samples))
        res.error = "samples fall where the density integrates to zero";
    if (res.outside > static_cast<size_t>(1e-5 * o.samples))
        res.error = "samples fall outside the domain";
    res.p_value = chi2_p_value(res.chi2, res.dof);
    return res;
}

/// A stable seed derived from a test's name (FNV-1a), so that every test draws its own
/// independent, reproducible samples.
inline uint64_t seed_from_name(const std::string& name) {
    uint64_t h = 0xcbf29ce484222325ULL;
    for (unsigned char c : name) h = (h ^ c) * 0x100000001b3ULL;
    return h;
}

/// Šidák-corrected significance level of one of `test_count` tests run at an overall
/// level of 1% (as Mitsuba's test suite; ~0.01 / test_count, the Bonferroni level).
inline double corrected_significance(int test_count, double overall = 0.01) {
    return 1.0 - std::pow(1.0 - overall, 1.0 / test_count);
}

// ---------------------------------------------------------------------------------------------
// Sphere parameterisation and BSDF helpers

/// (cos theta, phi in [0, 2 pi)) of a direction; dw = dcos(theta) dphi, so a solid-angle
/// density is also the density in these coordinates.
inline std::pair<double, double> sphere_coords(const femto::Vec3& w) {
    const double len = std::sqrt(double(w.x) * w.x + double(w.y) * w.y + double(w.z) * w.z);
    const double z = std::clamp(w.z / len, -1.0, 1.0);
    double phi = std::atan2(double(w.y), double(w.x));
    if (phi < 0) phi += 2 * kPi;
    return {z, phi};
}

inline femto::Vec3 sphere_direction(double cos_theta, double phi) {
    const double s = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
    return {static_cast<float>(s * std::cos(phi)), static_cast<float>(s * std::sin(phi)),
            static_cast<float>(cos_theta)};
}

/// Direction with polar angle theta_deg (from +z) and azimuth phi (radians).
inline femto::Vec3 direction_deg(double theta_deg, double phi = 0.0) {
    return sphere_direction(std::cos(theta_deg * kPi / 180.0), phi);
}

/// Builds a BSDF through the plugin host exactly as the scene loader would.
inline std::shared_ptr<femto::Bsdf> make_bsdf(const femto::Properties& props) {
    femto::ObjectPtr obj =
        femto::create_object(femto::PluginKind::Bsdf, props.plugin_type(), props);
    if (!obj || obj->kind() != femto::PluginKind::Bsdf) return nullptr;
    return std::static_pointer_cast<femto::Bsdf>(obj);
}

}  // namespace femto_test
