#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "btf/angular_filter.h"
#include "btf/pca.h"
#include "femto/btf_prefilter.h"

namespace femto::btf {

namespace {}  // namespace

std::array<float, 4> downsampling_weights(FilterKernel kernel) {
    if (kernel == FilterKernel::Box) return {0.f, 0.5f, 0.5f, 0.f};
    auto shape = [kernel](double x) {
        if (kernel == FilterKernel::Gaussian)
            return std::exp(-2 * x * x) - std::exp(-2 * 2.0 * 2.0);
        auto sinc = [](double t) { return t < 1e-9 ? 1.0 : std::sin(kPiD * t) / (kPiD * t); };
        return sinc(x) * sinc(x / 2);
    };
    const double inner = shape(0.5), outer = shape(1.5), sum = 2 * (inner + outer);
    return {float(outer / sum), float(inner / sum), float(inner / sum), float(outer / sum)};
}

namespace {

/// Texel index i of a texture of n texels that tiles (wraps around).
uint32_t wrap(int64_t i, uint32_t n) { return uint32_t(((i % n) + n) % n); }

/// Level L + 1's spatial factor from level L's: each parent texel is the weighted sum of the
/// 4 x 4 children around it (separable `weights`), wrapping around (the texture tiles), for one
/// channel of k components.
std::vector<float> downsample(const std::vector<float>& s, uint32_t w, uint32_t h, uint32_t k,
                              const std::array<float, 4>& weights, uint32_t& w2, uint32_t& h2) {
    w2 = std::max(1u, (w + 1) / 2);
    h2 = std::max(1u, (h + 1) / 2);
    std::vector<float> rows(size_t(w2) * h * k, 0.f);  // filtered along x
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w2; ++x)
            for (int t = 0; t < 4; ++t) {
                if (weights[t] == 0.f) continue;
                const float* in = &s[(size_t(y) * w + wrap(2 * int64_t(x) - 1 + t, w)) * k];
                float* o = &rows[(size_t(y) * w2 + x) * k];
                for (uint32_t c = 0; c < k; ++c) o[c] += weights[t] * in[c];
            }
    std::vector<float> out(size_t(w2) * h2 * k, 0.f);
    for (uint32_t y = 0; y < h2; ++y)
        for (uint32_t x = 0; x < w2; ++x)
            for (int t = 0; t < 4; ++t) {
                if (weights[t] == 0.f) continue;
                const float* in = &rows[(size_t(wrap(2 * int64_t(y) - 1 + t, h)) * w2 + x) * k];
                float* o = &out[(size_t(y) * w2 + x) * k];
                for (uint32_t c = 0; c < k; ++c) o[c] += weights[t] * in[c];
            }
    return out;
}

/// M' = F_l M F_v^T for each component's (lights x views) matrix M of an angular factor.
std::vector<float> filter_angular(const std::vector<float>& a, uint32_t nl, uint32_t nv, uint32_t k,
                                  const std::vector<double>& fl, const std::vector<double>& fv) {
    std::vector<float> out(a.size());
    std::vector<double> left(size_t(nl) * nv);  // F_l M
    for (uint32_t c = 0; c < k; ++c) {
        for (uint32_t l = 0; l < nl; ++l)
            for (uint32_t v = 0; v < nv; ++v) {
                double s = 0;
                for (uint32_t m = 0; m < nl; ++m)
                    s += fl[size_t(l) * nl + m] * a[(m + size_t(nl) * v) * k + c];
                left[size_t(l) * nv + v] = s;
            }
        for (uint32_t l = 0; l < nl; ++l)
            for (uint32_t v = 0; v < nv; ++v) {
                double s = 0;
                for (uint32_t m = 0; m < nv; ++m)
                    s += left[size_t(l) * nv + m] * fv[size_t(v) * nv + m];
                out[(l + size_t(nl) * v) * k + c] = float(s);
            }
    }
    return out;
}

}  // namespace

Hierarchy::Hierarchy(const Factors& base, const std::vector<Vec3>& lights,
                     const std::vector<Vec3>& views, const PrefilterSettings& settings)
    : lights_(base.lights),
      views_(base.views),
      components_(base.components),
      cones_(settings.cone_angles_deg) {
    if (lights.size() != base.lights || views.size() != base.views)
        throw std::invalid_argument("Hierarchy: the factors do not match the sampling");
    if (cones_.empty() || cones_[0] != 0 || !std::is_sorted(cones_.begin(), cones_.end()) ||
        std::adjacent_find(cones_.begin(), cones_.end()) != cones_.end() || cones_.back() > 90)
        throw std::invalid_argument("Hierarchy: cone angles must increase from 0 to at most 90");
    if (components_ > kMaxComponents)
        throw std::invalid_argument("Hierarchy: more than " + std::to_string(kMaxComponents) +
                                    " components");
    for (double& a : cones_) a *= kPiD / 180;
    // Bonn files sample lights and views alike: one filter then serves both.
    const AngularFilter light_filter(lights, settings.sh_degree, settings.regularization);
    std::vector<std::vector<double>> fl, fv;
    for (double a : cones_) fl.push_back(light_filter.matrix(settings.kernel, a));
    if (lights == views) {
        fv = fl;
    } else {
        const AngularFilter view_filter(views, settings.sh_degree, settings.regularization);
        for (double a : cones_) fv.push_back(view_filter.matrix(settings.kernel, a));
    }
    for (size_t i = 0; i < cones_.size(); ++i)
        for (size_t j = 0; j < cones_.size(); ++j)
            for (int c = 0; c < 3; ++c)
                angular_.push_back(
                    filter_angular(base.angular[c], lights_, views_, components_, fl[i], fv[j]));
    uint32_t w = base.width, h = base.height;
    widths_.push_back(w);
    heights_.push_back(h);
    for (int c = 0; c < 3; ++c) spatial_.push_back(base.spatial[c]);
    while (w > 1 || h > 1) {
        uint32_t w2 = 0, h2 = 0;
        for (int c = 0; c < 3; ++c)
            spatial_.push_back(downsample(spatial_[spatial_.size() - 3], w, h, components_,
                                          downsampling_weights(settings.kernel), w2, h2));
        w = w2;
        h = h2;
        widths_.push_back(w);
        heights_.push_back(h);
    }
}

Color Hierarchy::value(int level, uint32_t x, uint32_t y, size_t light_cone, size_t view_cone,
                       uint32_t l, uint32_t v) const {
    Color out;
    const size_t a_row = l + size_t(lights_) * v;
    const size_t s_row = x + size_t(widths_[size_t(level)]) * y;
    for (int c = 0; c < 3; ++c) {
        const float* a = &angular_[(light_cone * cones_.size() + view_cone) * 3 + size_t(c)]
                                  [a_row * components_];
        const float* s = &spatial_[size_t(level) * 3 + size_t(c)][s_row * components_];
        float sum = 0.f;
        for (uint32_t k = 0; k < components_; ++k) sum += a[k] * s[k];
        out[c] = sum;
    }
    return out;
}

void Hierarchy::bracket_cone(double angle, size_t& i0, size_t& i1, float& t) const {
    const size_t n = cones_.size();
    if (!(angle > 0) || n == 1) {
        i0 = i1 = 0;
        t = 0.f;
        return;
    }
    if (angle >= cones_.back()) {
        i0 = i1 = n - 1;
        t = 0.f;
        return;
    }
    i1 = size_t(std::upper_bound(cones_.begin(), cones_.end(), angle) - cones_.begin());
    i0 = i1 - 1;
    t = float((angle - cones_[i0]) / (cones_[i1] - cones_[i0]));
}

void Hierarchy::add_spatial(int level, Vec2 uv, float weight, float* s) const {
    const uint32_t w = widths_[size_t(level)];
    const BilinearTexels texels = bilinear_texels(uv, w, heights_[size_t(level)]);
    const uint32_t k = components_;
    for (int corner = 0; corner < 4; ++corner) {
        const float wc = weight * texels.weight[corner];
        if (wc == 0.f) continue;
        const size_t row = texels.x[corner & 1] + size_t(w) * texels.y[corner >> 1];
        for (int c = 0; c < 3; ++c) {
            const float* in = &spatial_[size_t(level) * 3 + size_t(c)][row * k];
            for (uint32_t i = 0; i < k; ++i) s[size_t(c) * k + i] += wc * in[i];
        }
    }
}

Color Hierarchy::lookup(Vec2 uv, double texel_ratio, double light_cone, double view_cone,
                        const DirectionMesh::Weights& light,
                        const DirectionMesh::Weights& view) const {
    // The spatial factor, blended between the two levels around log2(texel_ratio).
    float s[3 * kMaxComponents] = {};
    const double level =
        std::clamp(texel_ratio > 1 ? std::log2(texel_ratio) : 0.0, 0.0, double(levels() - 1));
    const int l0 = int(level), l1 = std::min(l0 + 1, levels() - 1);
    const float tl = float(level - l0);
    add_spatial(l0, uv, 1.f - tl, s);
    if (tl > 0.f) add_spatial(l1, uv, tl, s);
    return combine(s, light_cone, view_cone, light, view);
}

namespace {

/// The weights of texels first, first + 1, ... of a 1D texture, linear between texel centres
/// (texel i's centre at i), whose sum times the texels is the texture's mean over [a, b]:
/// w_i = (T(b - i) - T(a - i)) / (b - a) with T the integral of the unit tent. A point (b = a)
/// gets the linear interpolation's weights.
int box_weights(double a, double b, double* w, int max_count) {
    const int first = int(std::floor(a));  // texels below it have zero weight on [a, b]
    std::fill(w, w + max_count, 0.0);
    if (!(b - a > 1e-9)) {
        w[0] = 1 - (a - first);
        w[1] = a - first;
        return first;
    }
    auto tent_integral = [](double t) {
        if (t <= -1) return 0.0;
        if (t <= 0) return 0.5 * (t + 1) * (t + 1);
        if (t <= 1) return 1 - 0.5 * (1 - t) * (1 - t);
        return 1.0;
    };
    for (int j = 0; j < max_count; ++j) {
        const int i = first + j;
        w[j] = i > b + 1 ? 0.0 : (tent_integral(b - i) - tent_integral(a - i)) / (b - a);
    }
    return first;
}

}  // namespace

Color Hierarchy::lookup_box(Vec2 uv, Vec2 extent, double light_cone, double view_cone,
                            const DirectionMesh::Weights& light,
                            const DirectionMesh::Weights& view) const {
    // The finest level on which the rectangle spans at most kBoxTexels texels: at most
    // kBoxTexels + 2 texels per side have a weight.
    const double longest = std::max(std::abs(double(extent.x)), std::abs(double(extent.y)));
    int level = longest > kBoxTexels ? int(std::ceil(std::log2(longest / kBoxTexels))) : 0;
    level = std::clamp(level, 0, levels() - 1);
    const uint32_t w = widths_[size_t(level)], h = heights_[size_t(level)], k = components_;
    const double sx = double(w) / widths_[0], sy = double(h) / heights_[0];
    // The level's texel coordinates, texel centres at integers (as bilinear_texels()).
    const double fx = std::fmod(double(uv.x) * w - 0.5, double(w));
    const double fy = std::fmod((1.0 - double(uv.y)) * h - 0.5, double(h));
    // At most kBoxTexels wide: only the coarsest level (one texel, where any box is that
    // texel) and levels of odd sizes (rounded up) could be spanned by more.
    const double hx = std::min(0.5 * std::abs(double(extent.x)) * sx, kBoxTexels / 2);
    const double hy = std::min(0.5 * std::abs(double(extent.y)) * sy, kBoxTexels / 2);
    constexpr int kMax = int(kBoxTexels) + 3;
    double wx[kMax], wy[kMax];
    const int x0 = box_weights(fx - hx, fx + hx, wx, kMax);
    const int y0 = box_weights(fy - hy, fy + hy, wy, kMax);
    float s[3 * kMaxComponents] = {};
    for (int j = 0; j < kMax; ++j) {
        if (wy[j] == 0) continue;
        const size_t row_y = size_t(wrap(y0 + j, h)) * w;
        for (int i = 0; i < kMax; ++i) {
            const float wt = float(wx[i] * wy[j]);
            if (wt == 0.f) continue;
            const size_t row = row_y + wrap(x0 + i, w);
            for (int c = 0; c < 3; ++c) {
                const float* in = &spatial_[size_t(level) * 3 + size_t(c)][row * k];
                for (uint32_t q = 0; q < k; ++q) s[size_t(c) * k + q] += wt * in[q];
            }
        }
    }
    return combine(s, light_cone, view_cone, light, view);
}

Color Hierarchy::combine(const float* s, double light_cone, double view_cone,
                         const DirectionMesh::Weights& light,
                         const DirectionMesh::Weights& view) const {
    const uint32_t k = components_;
    // The angular factors of up to four cone pairs, each blended between the directions.
    size_t li[2], vi[2];
    float lt, vt;
    bracket_cone(light_cone, li[0], li[1], lt);
    bracket_cone(view_cone, vi[0], vi[1], vt);
    Color out(0.f);
    for (int pair = 0; pair < 4; ++pair) {
        const int a = pair & 1, b = pair >> 1;
        const float wp = (a ? lt : 1.f - lt) * (b ? vt : 1.f - vt);
        if (wp == 0.f) continue;
        const size_t index = li[a] * cones_.size() + vi[b];
        for (int c = 0; c < 3; ++c) {
            const std::vector<float>& angular = angular_[index * 3 + size_t(c)];
            float sum = 0.f;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    const float w = light.weight[i] * view.weight[j];
                    if (w == 0.f) continue;
                    const float* row =
                        &angular[(light.index[i] + size_t(lights_) * view.index[j]) * k];
                    const float* sc = &s[size_t(c) * k];
                    float dot = 0.f;
                    for (uint32_t q = 0; q < k; ++q) dot += row[q] * sc[q];
                    sum += w * dot;
                }
            out[c] += wp * sum;
        }
    }
    return out;
}

std::vector<double> Hierarchy::level_spectrum(int level, int c) const {
    // M = A S^T has the singular values sqrt(eig((A^T A)(S^T S))); with the Cholesky-free
    // symmetric form G = R_A (S^T S) R_A^T, where A^T A = R_A^T R_A, the eigenvalues are the
    // same. Here: eigen-decompose A^T A = V D V^T, take R = D^(1/2) V^T.
    const size_t k = components_;
    const std::vector<float>& a = angular_[size_t(c)];  // cones (0, 0)
    const std::vector<float>& s = spatial_[size_t(level) * 3 + size_t(c)];
    auto gram = [k](const std::vector<float>& m) {
        std::vector<double> g(k * k, 0.0);
        for (size_t r = 0; r < m.size() / k; ++r)
            for (size_t i = 0; i < k; ++i)
                for (size_t j = 0; j < k; ++j) g[i * k + j] += double(m[r * k + i]) * m[r * k + j];
        return g;
    };
    std::vector<double> d, v;
    symmetric_eigen(gram(a), k, d, v);
    const std::vector<double> ss = gram(s);
    std::vector<double> r(k * k), g(k * k, 0.0);
    for (size_t i = 0; i < k; ++i)
        for (size_t j = 0; j < k; ++j) r[i * k + j] = std::sqrt(std::max(0.0, d[i])) * v[j * k + i];
    for (size_t i = 0; i < k; ++i)
        for (size_t j = 0; j < k; ++j)
            for (size_t p = 0; p < k; ++p)
                for (size_t q = 0; q < k; ++q)
                    g[i * k + j] += r[i * k + p] * ss[p * k + q] * r[j * k + q];
    std::vector<double> sigma2, unused;
    symmetric_eigen(g, k, sigma2, unused);
    for (double& x : sigma2) x = std::sqrt(std::max(0.0, x));
    return sigma2;
}

uint64_t Hierarchy::memory_bytes() const {
    uint64_t n = 0;
    for (const auto& v : angular_) n += v.size() * sizeof(float);
    for (const auto& v : spatial_) n += v.size() * sizeof(float);
    return n;
}

}  // namespace femto::btf
