// The prefiltered BTF hierarchy (Jarabo, Plenoptic Light Transport, ch. 3, Fig. 3.5): spatial
// levels from the texture down to one texel, each in versions filtered over cones of light and
// view directions of half-angles 0, 15, 30 and 45 degrees (configurable).
//
// The hierarchy is kept factorized, per colour channel, as the Bonn DFMF files are: a BTF of
// rank k is B(x, l, v) = sum_c A_c(l, v) S_c(x). Both filters are linear, and the spatial one
// acts on S only, the angular one on A only, so the hierarchy is a set of angular factors (one
// per pair of cone angles, btf/angular_filter.h) and a set of spatial factors (one per level,
// box-averaged 2 x 2 with wrapping): level L, angles (i, j) = sum_c A_c^(i,j) S_c^(L).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "btf/angular_filter.h"
#include "femto/btf.h"

namespace femto::btf {

/// A BTF as rank-k factors per colour channel: angular[c] is (lights x views) x k with the
/// light fastest, spatial[c] is (width x height) x k with x fastest.
struct Factors {
    uint32_t width = 0, height = 0, lights = 0, views = 0, components = 0;
    std::array<std::vector<float>, 3> angular, spatial;
};

/// The factors of a BTF whose decoding is linear in its stored factors (RGB DFMF and FMF
/// without dynamic-range reduction; the cosine flag folds into the angular factor); false
/// otherwise (BDI, colour model 11, log data), which need a factorization of their values.
bool linear_factors(const Data& data, Factors& out);

struct PrefilterSettings {
    FilterKernel kernel = FilterKernel::Box;
    std::vector<double> cone_angles_deg = {0, 15, 30, 45};
    int sh_degree = 2;              ///< of the angular fit (btf/angular_filter.h)
    double regularization = 1e-10;  ///< of the angular fit
};

class Hierarchy {
public:
    Hierarchy(const Factors& base, const std::vector<Vec3>& lights, const std::vector<Vec3>& views,
              const PrefilterSettings& settings);
    int levels() const { return int(widths_.size()); }
    uint32_t width(int level) const { return widths_[size_t(level)]; }
    uint32_t height(int level) const { return heights_[size_t(level)]; }
    size_t cone_count() const { return cones_; }
    /// Level `level`'s texel (x, y), filtered over light cones `light_cone` and view cones
    /// `view_cone` (indices into the settings' angles), at sampled light l and view v.
    Color value(int level, uint32_t x, uint32_t y, size_t light_cone, size_t view_cone, uint32_t l,
                uint32_t v) const;
    uint64_t memory_bytes() const;

private:
    uint32_t lights_, views_, components_;
    size_t cones_;
    std::vector<uint32_t> widths_, heights_;
    // angular_[(i * cones + j) * 3 + c]: (lights x views) x k; spatial_[level * 3 + c].
    std::vector<std::vector<float>> angular_, spatial_;
};

}  // namespace femto::btf
