#include "btf/pca.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "femto/btf_prefilter.h"
#include "femto/random.h"

namespace femto::btf {

namespace {

/// Per colour channel: a (rows x cols) row-major matrix.
using Channels = std::array<std::vector<double>, 3>;

/// Calls visit(s, column) for every texel s (x + width y) with the decoded values of all
/// (light, view) pairs of that texel, per channel (l + lights v).
template <typename Visit>
void for_each_column(const Data& data, Visit&& visit) {
    const Header& h = data.header();
    const size_t nl = h.lights.size(), nv = h.views.size();
    Channels column;
    for (auto& c : column) c.resize(nl * nv);
    for (uint32_t y = 0; y < h.height; ++y)
        for (uint32_t x = 0; x < h.width; ++x) {
            for (size_t v = 0; v < nv; ++v)
                for (size_t l = 0; l < nl; ++l) {
                    const Color b = data.value(x, y, uint32_t(l), uint32_t(v));
                    for (int c = 0; c < 3; ++c) column[c][l + nl * v] = b[c];
                }
            visit(x + size_t(h.width) * y, column);
        }
}

/// Orthonormalizes the r columns of the (n x r) matrix q in place (modified Gram-Schmidt,
/// twice, for the loss of orthogonality of nearly dependent columns).
void orthonormalize(std::vector<double>& q, size_t n, size_t r) {
    for (int pass = 0; pass < 2; ++pass)
        for (size_t j = 0; j < r; ++j) {
            for (size_t i = 0; i < j; ++i) {
                double d = 0;
                for (size_t a = 0; a < n; ++a) d += q[a * r + i] * q[a * r + j];
                for (size_t a = 0; a < n; ++a) q[a * r + j] -= d * q[a * r + i];
            }
            double norm = 0;
            for (size_t a = 0; a < n; ++a) norm += q[a * r + j] * q[a * r + j];
            norm = std::sqrt(norm);
            for (size_t a = 0; a < n; ++a) q[a * r + j] = norm > 1e-300 ? q[a * r + j] / norm : 0.0;
        }
}

/// z = column^T q (a row of r) for one texel's column.
void project(const std::vector<double>& column, const std::vector<double>& q, size_t r, double* z) {
    std::fill(z, z + r, 0.0);
    for (size_t a = 0; a < column.size(); ++a)
        for (size_t j = 0; j < r; ++j) z[j] += column[a] * q[a * r + j];
}

}  // namespace

void symmetric_eigen(std::vector<double> a, size_t n, std::vector<double>& values,
                     std::vector<double>& vectors) {
    vectors.assign(n * n, 0.0);
    for (size_t i = 0; i < n; ++i) vectors[i * n + i] = 1.0;
    for (int sweep = 0; sweep < 100; ++sweep) {
        double off = 0;
        for (size_t p = 0; p < n; ++p)
            for (size_t q = p + 1; q < n; ++q) off += a[p * n + q] * a[p * n + q];
        if (off < 1e-30) break;
        for (size_t p = 0; p < n; ++p)
            for (size_t q = p + 1; q < n; ++q) {
                if (std::abs(a[p * n + q]) < 1e-300) continue;
                const double theta = (a[q * n + q] - a[p * n + p]) / (2 * a[p * n + q]);
                const double t =
                    (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::hypot(theta, 1.0));
                const double c = 1 / std::sqrt(t * t + 1), s = t * c;
                for (size_t k = 0; k < n; ++k) {  // A <- A J, V <- V J
                    const double akp = a[k * n + p], akq = a[k * n + q];
                    a[k * n + p] = c * akp - s * akq;
                    a[k * n + q] = s * akp + c * akq;
                    const double vkp = vectors[k * n + p], vkq = vectors[k * n + q];
                    vectors[k * n + p] = c * vkp - s * vkq;
                    vectors[k * n + q] = s * vkp + c * vkq;
                }
                for (size_t k = 0; k < n; ++k) {  // A <- J^T A
                    const double apk = a[p * n + k], aqk = a[q * n + k];
                    a[p * n + k] = c * apk - s * aqk;
                    a[q * n + k] = s * apk + c * aqk;
                }
            }
    }
    std::vector<size_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(),
              [&](size_t i, size_t j) { return a[i * n + i] > a[j * n + j]; });
    std::vector<double> sorted(n * n);
    values.resize(n);
    for (size_t j = 0; j < n; ++j) {
        values[j] = a[order[j] * n + order[j]];
        for (size_t i = 0; i < n; ++i) sorted[i * n + j] = vectors[i * n + order[j]];
    }
    vectors = std::move(sorted);
}

Factors factorize(const Data& data, const PcaSettings& settings, PcaReport* report) {
    const Header& h = data.header();
    const size_t rows = h.lights.size() * h.views.size(), cols = size_t(h.width) * h.height;
    const size_t k = std::min<size_t>({settings.components, rows, cols});
    const size_t r = std::min<size_t>(k + settings.oversampling, std::min(rows, cols));
    // Range finder: Y = M Omega (Gaussian Omega, drawn per texel in a fixed order), ||M||_F^2.
    Channels y, z;
    std::array<double, 3> norm2{};
    for (int c = 0; c < 3; ++c) y[c].assign(rows * r, 0.0);
    Pcg32 rng(settings.seed, 0x5ca1ab1e);
    std::vector<double> omega(r);
    for_each_column(data, [&](size_t, const Channels& col) {
        for (size_t j = 0; j < r; ++j) {  // Box-Muller
            const double u1 = 1.0 - rng.next_double(), u2 = rng.next_double();
            omega[j] = std::sqrt(-2 * std::log(u1)) * std::cos(2 * 3.14159265358979323846 * u2);
        }
        for (int c = 0; c < 3; ++c)
            for (size_t a = 0; a < rows; ++a) {
                norm2[c] += col[c][a] * col[c][a];
                for (size_t j = 0; j < r; ++j) y[c][a * r + j] += col[c][a] * omega[j];
            }
    });
    std::vector<double> zs(r);
    for (uint32_t it = 0; it < settings.power_iterations; ++it) {  // Y <- M M^T orth(Y)
        Channels next;
        for (int c = 0; c < 3; ++c) {
            orthonormalize(y[c], rows, r);
            next[c].assign(rows * r, 0.0);
        }
        for_each_column(data, [&](size_t, const Channels& col) {
            for (int c = 0; c < 3; ++c) {
                project(col[c], y[c], r, zs.data());
                for (size_t a = 0; a < rows; ++a)
                    for (size_t j = 0; j < r; ++j) next[c][a * r + j] += col[c][a] * zs[j];
            }
        });
        y = std::move(next);
    }
    for (int c = 0; c < 3; ++c) {
        orthonormalize(y[c], rows, r);
        z[c].assign(cols * r, 0.0);
    }
    for_each_column(data, [&](size_t s, const Channels& col) {  // Z = M^T Q = B^T
        for (int c = 0; c < 3; ++c) project(col[c], y[c], r, &z[c][s * r]);
    });
    Factors f;
    f.width = h.width;
    f.height = h.height;
    f.lights = uint32_t(h.lights.size());
    f.views = uint32_t(h.views.size());
    f.components = uint32_t(k);
    for (int c = 0; c < 3; ++c) {
        // B B^T = Z^T Z = U diag(sigma^2) U^T; angular = Q U_k, spatial = Z U_k = V_k Sigma_k.
        std::vector<double> gram(r * r, 0.0), sigma2, u;
        for (size_t s = 0; s < cols; ++s)
            for (size_t i = 0; i < r; ++i)
                for (size_t j = 0; j < r; ++j) gram[i * r + j] += z[c][s * r + i] * z[c][s * r + j];
        symmetric_eigen(gram, r, sigma2, u);
        f.angular[c].assign(rows * k, 0.f);
        f.spatial[c].assign(cols * k, 0.f);
        for (size_t i = 0; i < k; ++i) {
            for (size_t a = 0; a < rows; ++a) {
                double v = 0;
                for (size_t j = 0; j < r; ++j) v += y[c][a * r + j] * u[j * r + i];
                f.angular[c][a * k + i] = float(v);
            }
            for (size_t s = 0; s < cols; ++s) {
                double v = 0;
                for (size_t j = 0; j < r; ++j) v += z[c][s * r + j] * u[j * r + i];
                f.spatial[c][s * k + i] = float(v);
            }
        }
        if (report) {
            double kept = 0;
            report->singular_values[c].clear();
            for (size_t i = 0; i < k; ++i) {
                kept += std::max(0.0, sigma2[i]);
                report->singular_values[c].push_back(std::sqrt(std::max(0.0, sigma2[i])));
            }
            report->energy_kept[c] = norm2[c] > 0 ? kept / norm2[c] : 1.0;
            report->relative_error[c] =
                norm2[c] > 0 ? std::sqrt(std::max(0.0, norm2[c] - kept) / norm2[c]) : 0.0;
        }
    }
    return f;
}

}  // namespace femto::btf
