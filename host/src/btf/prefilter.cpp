#include "btf/prefilter.h"

#include <cmath>
#include <stdexcept>

namespace femto::btf {

namespace {

/// Level L + 1's spatial factor from level L's: the mean of each 2 x 2 block of texels,
/// wrapping around (the texture tiles), for one channel of k components.
std::vector<float> downsample(const std::vector<float>& s, uint32_t w, uint32_t h, uint32_t k,
                              uint32_t& w2, uint32_t& h2) {
    w2 = std::max(1u, (w + 1) / 2);
    h2 = std::max(1u, (h + 1) / 2);
    std::vector<float> out(size_t(w2) * h2 * k, 0.f);
    for (uint32_t y = 0; y < h2; ++y)
        for (uint32_t x = 0; x < w2; ++x) {
            float* o = &out[(size_t(y) * w2 + x) * k];
            for (uint32_t dy = 0; dy < 2; ++dy)
                for (uint32_t dx = 0; dx < 2; ++dx) {
                    const uint32_t cx = (2 * x + dx) % w, cy = (2 * y + dy) % h;
                    const float* in = &s[(size_t(cy) * w + cx) * k];
                    for (uint32_t c = 0; c < k; ++c) o[c] += 0.25f * in[c];
                }
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
      cones_(settings.cone_angles_deg.size()) {
    if (lights.size() != base.lights || views.size() != base.views || cones_ == 0)
        throw std::invalid_argument("Hierarchy: the factors do not match the sampling");
    const AngularFilter light_filter(lights, settings.sh_degree, settings.regularization);
    const AngularFilter view_filter(views, settings.sh_degree, settings.regularization);
    std::vector<std::vector<double>> fl, fv;
    for (double a : settings.cone_angles_deg) {
        fl.push_back(light_filter.matrix(settings.kernel, a * kPiD / 180));
        fv.push_back(view_filter.matrix(settings.kernel, a * kPiD / 180));
    }
    for (size_t i = 0; i < cones_; ++i)
        for (size_t j = 0; j < cones_; ++j)
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
            spatial_.push_back(
                downsample(spatial_[spatial_.size() - 3], w, h, components_, w2, h2));
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
        const float* a =
            &angular_[(light_cone * cones_ + view_cone) * 3 + size_t(c)][a_row * components_];
        const float* s = &spatial_[size_t(level) * 3 + size_t(c)][s_row * components_];
        float sum = 0.f;
        for (uint32_t k = 0; k < components_; ++k) sum += a[k] * s[k];
        out[c] = sum;
    }
    return out;
}

uint64_t Hierarchy::memory_bytes() const {
    uint64_t n = 0;
    for (const auto& v : angular_) n += v.size() * sizeof(float);
    for (const auto& v : spatial_) n += v.size() * sizeof(float);
    return n;
}

}  // namespace femto::btf
