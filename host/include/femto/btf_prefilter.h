// femto public API: the prefiltered hierarchy of a BTF (Jarabo, Plenoptic Light Transport,
// ch. 3, Fig. 3.5): spatial levels from the texture down to one texel, each in versions filtered
// over cones of light and view directions (half-angles 0, 15, 30, 45 degrees by default), and
// the lookup that selects and interpolates them from a pixel's footprint. docs/btf.md explains
// the method; the `btf` material uses it.
//
// The hierarchy is kept factorized per colour channel, as the Bonn DFMF files are: a BTF of
// rank k is B(x, l, v) = sum_i A_i(l, v) S_i(x). Both filters are linear; the spatial one (2 x 2
// box means, wrapping) acts on S only, the angular one (a spherical-harmonic fit scaled by the
// kernel's Funk-Hecke coefficients, plus a cone quadrature of what the fit leaves) on A only.
// Files whose decoding is not linear in their factors (BDI, colour model 11, log data) are
// factorized first by PCA (a randomized SVD).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "femto/btf.h"
#include "femto/direction_mesh.h"

namespace femto::btf {

enum class FilterKernel { Box, Gaussian, Lanczos };

/// A BTF as rank-k factors per colour channel: angular[c] is (lights x views) x k with the
/// light fastest, spatial[c] is (width x height) x k with x fastest.
struct Factors {
    uint32_t width = 0, height = 0, lights = 0, views = 0, components = 0;
    std::array<std::vector<float>, 3> angular, spatial;
};

/// The factors of a BTF whose decoding is linear in its stored factors (RGB DFMF and FMF
/// without dynamic-range reduction; the cosine flag folds into the angular factor); false
/// otherwise (BDI, colour model 11, log data), which need factorize().
bool linear_factors(const Data& data, Factors& out);

struct PcaSettings {
    uint32_t components = 16;
    uint32_t oversampling = 8;  ///< extra random directions of the range finder
    uint32_t power_iterations = 2;
    uint64_t seed = 1;
};

struct PcaReport {
    std::array<std::vector<double>, 3> singular_values;  ///< per channel, the k kept
    std::array<double, 3> energy_kept{};     ///< sum of kept sigma^2 / squared Frobenius norm
    std::array<double, 3> relative_error{};  ///< ||M - M_k||_F / ||M||_F
};

/// PCA: per channel, the best rank-k approximation of the (lights x views) x texels matrix of
/// decoded values (Halko, Martinsson and Tropp's randomized SVD: a range finder with power
/// iterations, then the exact SVD of the projected matrix; 2 + power_iterations passes over the
/// data). k is clamped to the matrix's smaller side.
Factors factorize(const Data& data, const PcaSettings& settings, PcaReport* report = nullptr);

/// The weights of the four children along one axis (offsets -1.5, -0.5, 0.5, 1.5 child texels
/// from the parent's centre) by which a level's texel is made from the finer level: box = the
/// two under the parent (a 2 x 2 mean); Gaussian and Lanczos = pbrt's shapes over a radius of
/// 2 child texels (Gaussian alpha = 2; Lanczos sinc(x) sinc(x / 2)), normalized to sum to 1.
std::array<float, 4> downsampling_weights(FilterKernel kernel);

/// The Funk-Hecke coefficients lambda_0 .. lambda_{max_band} of `kernel` over cones of
/// half-angle `alpha` (radians): averaging a band-l function over the cones scales it by
/// lambda_l (box: (P_{l-1}(cos a) - P_{l+1}(cos a)) / ((2l + 1)(1 - cos a)); the others by
/// quadrature). All 1 for alpha = 0.
std::vector<double> kernel_band_scales(FilterKernel kernel, double alpha, int max_band);

struct PrefilterSettings {
    FilterKernel kernel = FilterKernel::Box;
    std::vector<double> cone_angles_deg = {0, 15, 30, 45};  ///< increasing, from 0
    int sh_degree = 2;                                      ///< of the angular fit
    double regularization = 1e-10;                          ///< of the angular fit
};

class Hierarchy {
public:
    Hierarchy(const Factors& base, const std::vector<Vec3>& lights, const std::vector<Vec3>& views,
              const PrefilterSettings& settings);
    int levels() const { return int(widths_.size()); }
    uint32_t width(int level) const { return widths_[size_t(level)]; }
    uint32_t height(int level) const { return heights_[size_t(level)]; }
    size_t cone_count() const { return cones_.size(); }
    uint32_t components() const { return components_; }
    /// Level `level`'s texel (x, y), filtered over light cones `light_cone` and view cones
    /// `view_cone` (indices into the settings' angles), at sampled light l and view v.
    Color value(int level, uint32_t x, uint32_t y, size_t light_cone, size_t view_cone, uint32_t l,
                uint32_t v) const;
    /// What one pixel sees of the BTF at texture position uv (already times uv_scale; it wraps):
    /// `texel_ratio` texels per pixel (the level is its log2, linear between levels, the
    /// finest below 1), light and view cone half-angles in radians (linear between the
    /// settings' angles, clamped to them), and the light and view directions' interpolation
    /// weights between the sampled directions.
    Color lookup(Vec2 uv, double texel_ratio, double light_cone, double view_cone,
                 const DirectionMesh::Weights& light, const DirectionMesh::Weights& view) const;
    /// As lookup(), but the spatial factor is the exact mean of a level's bilinear texture
    /// over the rectangle of `extent` finest-level texels (width along u, height along v)
    /// centred at uv: a box filter over a pixel's footprint instead of a mip-map's
    /// texel-aligned blocks. The level is the finest on which the rectangle spans at most
    /// kBoxTexels texels along both sides (the finest level up to footprints of that size).
    Color lookup_box(Vec2 uv, Vec2 extent, double light_cone, double view_cone,
                     const DirectionMesh::Weights& light, const DirectionMesh::Weights& view) const;
    static constexpr double kBoxTexels = 8;
    uint64_t memory_bytes() const;
    /// The singular values (decreasing) of level `level`'s unfiltered-cone matrix of channel c,
    /// (lights x views) x texels: how many components that level needs for a share of its
    /// energy (thesis Fig. 3.17: coarser levels need far fewer).
    std::vector<double> level_spectrum(int level, int c) const;

    static constexpr uint32_t kMaxComponents = 512;  ///< lookup() keeps k floats on the stack

    /// Writes the hierarchy to `path` (binary, this machine's byte order), tagged with `key`.
    void save(const std::string& path, const std::string& key) const;
    /// The hierarchy saved at `path` with the same `key`, or null (no file, another key, or a
    /// file that does not read back whole).
    static std::shared_ptr<Hierarchy> load(const std::string& path, const std::string& key);

private:
    Hierarchy() = default;
    /// The two nearest cone indices around `angle` and the weight of the second.
    void bracket_cone(double angle, size_t& i0, size_t& i1, float& t) const;
    /// Adds weight x the bilinear spatial factor of level `level` at uv to s (3 x k).
    void add_spatial(int level, Vec2 uv, float weight, float* s) const;
    /// The angular factors at the cones and directions, dotted with the spatial factor s.
    Color combine(const float* s, double light_cone, double view_cone,
                  const DirectionMesh::Weights& light, const DirectionMesh::Weights& view) const;

    uint32_t lights_ = 0, views_ = 0, components_ = 0;
    std::vector<double> cones_;  // radians
    std::vector<uint32_t> widths_, heights_;
    // angular_[(i * cones + j) * 3 + c]: (lights x views) x k; spatial_[level * 3 + c].
    std::vector<std::vector<float>> angular_, spatial_;
};

/// What prefiltered() did, for a log line.
struct PrefilterReport {
    bool from_cache = false;
    std::string cache_file;     ///< empty when caching is off or impossible
    std::string cache_problem;  ///< why the cache could not be written, if it could not
    bool factorized = false;    ///< PCA was needed (BDI, log data)
    PcaReport pca;
    double seconds = 0;
    uint64_t memory_bytes = 0;
};

/// The hierarchy of the BTF file `path` (read as `data`): loaded from the cache file next to
/// it when one matches (same file contents by size and CRC-32, same settings), else built
/// (from the file's factors, or from PCA) and, with `use_cache`, written there.
std::shared_ptr<const Hierarchy> prefiltered(const std::string& path, const Data& data,
                                             const PrefilterSettings& settings,
                                             const PcaSettings& pca, bool use_cache,
                                             PrefilterReport& report);

}  // namespace femto::btf
