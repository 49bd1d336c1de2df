#include "btf/angular_filter.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "femto/direction_mesh.h"

namespace femto::btf {

namespace {

double legendre(int l, double x) {
    if (l < 0) return 1.0;  // P_{-1} := 1 makes the box formula give lambda_0 = 1
    double p0 = 1.0, p1 = x;
    if (l == 0) return p0;
    for (int k = 2; k <= l; ++k) {
        const double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    return p1;
}

/// The kernel's value at angle theta from the cone's axis, for a cone of half-angle alpha
/// (pbrt's shapes over u = theta / alpha in [0, 1]).
double kernel_value(FilterKernel kernel, double theta, double alpha) {
    const double u = theta / alpha;
    if (u > 1.0) return 0.0;
    switch (kernel) {
        case FilterKernel::Box:
            return 1.0;
        case FilterKernel::Gaussian:
            return std::exp(-2.0 * u * u) - std::exp(-2.0);
        case FilterKernel::Lanczos: {
            // Three lobes of sinc inside the cone, windowed by the central lobe of sinc(x/3).
            const double x = 3.0 * u;
            auto sinc = [](double t) { return t < 1e-8 ? 1.0 : std::sin(kPiD * t) / (kPiD * t); };
            return sinc(x) * sinc(x / 3.0);
        }
    }
    return 0.0;
}

/// Solves A x = b for a symmetric positive definite A (n x n, row-major) in place, for each of
/// the `columns` right-hand sides stored as the columns of b (n x columns).
void cholesky_solve(std::vector<double> a, size_t n, std::vector<double>& b, size_t columns) {
    for (size_t j = 0; j < n; ++j) {
        double d = a[j * n + j];
        for (size_t k = 0; k < j; ++k) d -= a[j * n + k] * a[j * n + k];
        if (!(d > 0))
            throw std::runtime_error("AngularFilter: the fit's normal matrix is singular");
        a[j * n + j] = std::sqrt(d);
        for (size_t i = j + 1; i < n; ++i) {
            double s = a[i * n + j];
            for (size_t k = 0; k < j; ++k) s -= a[i * n + k] * a[j * n + k];
            a[i * n + j] = s / a[j * n + j];
        }
    }
    for (size_t c = 0; c < columns; ++c) {
        for (size_t i = 0; i < n; ++i) {  // L y = b
            double s = b[i * columns + c];
            for (size_t k = 0; k < i; ++k) s -= a[i * n + k] * b[k * columns + c];
            b[i * columns + c] = s / a[i * n + i];
        }
        for (size_t i = n; i-- > 0;) {  // L^T x = y
            double s = b[i * columns + c];
            for (size_t k = i + 1; k < n; ++k) s -= a[k * n + i] * b[k * columns + c];
            b[i * columns + c] = s / a[i * n + i];
        }
    }
}

}  // namespace

void sh_eval(int degree, const Vec3& d, double* out) {
    const double z = std::clamp(double(d.z), -1.0, 1.0);
    const double sin_theta = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = std::atan2(double(d.y), double(d.x));
    for (int m = 0; m <= degree; ++m) {
        // Associated Legendre P_m^m, then upward in l (no Condon-Shortley phase).
        double pmm = 1.0;
        for (int k = 1; k <= m; ++k) pmm *= (2 * k - 1) * sin_theta;
        double p_prev = 0.0, p = pmm;
        for (int l = m; l <= degree; ++l) {
            if (l > m) {
                const double next = ((2 * l - 1) * z * p - (l + m - 1) * p_prev) / (l - m);
                p_prev = p;
                p = next;
            }
            double ratio = 1.0;  // (l - m)! / (l + m)!
            for (int k = l - m + 1; k <= l + m; ++k) ratio /= k;
            const double norm = std::sqrt((2 * l + 1) / (4 * kPiD) * ratio);
            if (m == 0) {
                out[l * (l + 1)] = norm * p;
            } else {
                out[l * (l + 1) + m] = std::sqrt(2.0) * norm * p * std::cos(m * phi);
                out[l * (l + 1) - m] = std::sqrt(2.0) * norm * p * std::sin(m * phi);
            }
        }
    }
}

std::vector<double> kernel_band_scales(FilterKernel kernel, double alpha, int max_band) {
    std::vector<double> scale(size_t(max_band) + 1, 1.0);
    if (alpha < 1e-6) return scale;
    const double c = std::cos(alpha);
    if (kernel == FilterKernel::Box) {
        for (int l = 0; l <= max_band; ++l)
            scale[l] = (legendre(l - 1, c) - legendre(l + 1, c)) / ((2 * l + 1) * (1 - c));
        return scale;
    }
    // Composite Simpson over theta in [0, alpha] of k(theta) P_l(cos theta) sin theta.
    constexpr int kSteps = 4096;
    std::vector<double> sum(size_t(max_band) + 1, 0.0);
    double total = 0.0;
    for (int i = 0; i <= kSteps; ++i) {
        const double theta = alpha * i / kSteps;
        const double w = (i == 0 || i == kSteps) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        const double k = w * kernel_value(kernel, theta, alpha) * std::sin(theta);
        total += k;
        for (int l = 0; l <= max_band; ++l) sum[l] += k * legendre(l, std::cos(theta));
    }
    for (int l = 0; l <= max_band; ++l) scale[l] = sum[l] / total;
    return scale;
}

AngularFilter::AngularFilter(const std::vector<Vec3>& directions, int degree, double regularization)
    : directions_(directions), mesh_(directions), n_(directions.size()), degree_(degree) {
    const size_t count = size_t(sh_count(degree));
    if (degree < 0 || count > n_)
        throw std::invalid_argument("AngularFilter: degree " + std::to_string(degree) + " needs " +
                                    std::to_string(count) + " directions, there are " +
                                    std::to_string(n_));
    basis_.resize(n_ * count);
    for (size_t i = 0; i < n_; ++i) sh_eval(degree, directions[i], &basis_[i * count]);
    // Y+ = (Y^T Y + eps R)^-1 Y^T, R = diag(l^2 (l + 1)^2).
    std::vector<double> normal(count * count, 0.0);
    for (size_t a = 0; a < count; ++a)
        for (size_t b = 0; b < count; ++b)
            for (size_t i = 0; i < n_; ++i)
                normal[a * count + b] += basis_[i * count + a] * basis_[i * count + b];
    for (int l = 0; l <= degree; ++l)
        for (int m = -l; m <= l; ++m) {
            const size_t a = size_t(l * (l + 1) + m);
            normal[a * count + a] += regularization * double(l * l * (l + 1) * (l + 1));
        }
    inverse_.resize(count * n_);
    for (size_t a = 0; a < count; ++a)
        for (size_t i = 0; i < n_; ++i) inverse_[a * n_ + i] = basis_[i * count + a];
    cholesky_solve(normal, count, inverse_, n_);
}

std::vector<double> AngularFilter::cone_quadrature(FilterKernel kernel, double alpha) const {
    std::vector<double> q(n_ * n_, 0.0);
    if (alpha < 1e-6) {
        for (size_t i = 0; i < n_; ++i) q[i * n_ + i] = 1.0;
        return q;
    }
    constexpr int kRings = 12, kAzimuths = 24;  // midpoint rule in theta and phi
    for (size_t i = 0; i < n_; ++i) {
        const Frame frame(directions_[i]);
        double total = 0.0;
        for (int r = 0; r < kRings; ++r) {
            const double theta = alpha * (r + 0.5) / kRings;
            const double w = kernel_value(kernel, theta, alpha) * std::sin(theta);
            for (int a = 0; a < kAzimuths; ++a) {
                const double phi = 2 * kPiD * (a + 0.5) / kAzimuths;
                const Vec3 local(float(std::sin(theta) * std::cos(phi)),
                                 float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)));
                const DirectionMesh::Weights iw = mesh_.interpolate(frame.to_world(local));
                for (int k = 0; k < 3; ++k) q[i * n_ + iw.index[k]] += w * iw.weight[k];
                total += w;
            }
        }
        for (size_t j = 0; j < n_; ++j) q[i * n_ + j] /= total;
    }
    return q;
}

std::vector<double> AngularFilter::matrix(FilterKernel kernel, double alpha) const {
    // F = Y Lambda Y+ + Q (I - Y Y+) = Q + (Y Lambda - Q Y) Y+.
    const size_t count = size_t(sh_count(degree_));
    const std::vector<double> scale = kernel_band_scales(kernel, alpha, degree_);
    std::vector<double> f = cone_quadrature(kernel, alpha);
    const std::vector<double> q = f;
    std::vector<double> row(count);
    for (size_t i = 0; i < n_; ++i) {
        for (int l = 0; l <= degree_; ++l)
            for (int m = -l; m <= l; ++m) {
                const size_t a = size_t(l * (l + 1) + m);
                double qy = 0.0;
                for (size_t j = 0; j < n_; ++j) qy += q[i * n_ + j] * basis_[j * count + a];
                row[a] = basis_[i * count + a] * scale[size_t(l)] - qy;
            }
        for (size_t j = 0; j < n_; ++j) {
            double s = 0.0;
            for (size_t a = 0; a < count; ++a) s += row[a] * inverse_[a * n_ + j];
            f[i * n_ + j] += s;
        }
    }
    return f;
}

}  // namespace femto::btf
