// Synthetic BTFs with closed forms (`femto btf synth`, the BTF tests, docs/btf.md): measured
// databases cannot be downloaded everywhere, and a closed form tells right from nearly right.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "femto/btf.h"

namespace femto::btf::synth {

/// BTF A: a separable, low-order spherical-harmonic BTF of rank 3 per channel,
///   B_c(x, y, l, v) = sum_{k=0..2} T_ck(x, y) G_k(l, v),
/// with angular terms of known bands in l and in v,
///   G_0 = 1 (band 0, 0),  G_1 = (l.a)(v.b) (band 1, 1),  G_2 = P_2(l.c) (band 2, 0),
/// (a, b, c fixed tilted unit vectors, so B is anisotropic and not reciprocal) and spatial
/// terms T_ck = m_ck + s_ck cos(2 pi fx_k (x + 1/2) / W + p_k) cos(2 pi fy_k (y + 1/2) / H + q_k)
/// (integer frequencies: the texture tiles). B stays >= 0.03 everywhere.
/// Filtering has closed forms: a box average over a block of texels is a product of two
/// Dirichlet sums, and by Funk-Hecke the average of a band-l term over a cap of half-angle
/// alpha is the term at the cap's centre times lambda_1 = (1 + cos alpha) / 2 (band 1) or
/// lambda_2 = cos alpha (1 + cos alpha) / 2 (band 2).
class HarmonicBtf {
public:
    HarmonicBtf(uint32_t width, uint32_t height) : width_(width), height_(height) {}
    uint32_t width() const { return width_; }
    uint32_t height() const { return height_; }

    /// T_ck at texel (x, y).
    double spatial(int c, int k, uint32_t x, uint32_t y) const;
    /// The mean of T_ck over the texels [x0, x0 + nx) x [y0, y0 + ny) (wrapping), in closed form.
    double spatial_box_mean(int c, int k, uint32_t x0, uint32_t y0, uint32_t nx, uint32_t ny) const;
    /// T_ck at texel (x, y) of the level `level` steps coarser, made by repeatedly downsampling
    /// with the separable child `weights` (femto/btf_prefilter.h's downsampling_weights, which
    /// wrap): a cosine of frequency w in a level's texels comes out of one step scaled by
    /// H(w) = sum_t weights[t] cos(w (t - 1.5)), its frequency doubled, its phase kept.
    double spatial_downsampled(int c, int k, int level, uint32_t x, uint32_t y,
                               const std::array<float, 4>& weights) const;
    /// G_k(l, v) for any directions.
    static double angular(int k, const Vec3& l, const Vec3& v);
    /// The mean of G_k over lights in the cap of half-angle alpha_l around l and views in the
    /// cap of half-angle alpha_v around v (Funk-Hecke).
    static double angular_cap_mean(int k, const Vec3& l, const Vec3& v, double alpha_l,
                                   double alpha_v);
    /// G_k averaged over cones with band scales lambda (kernel_band_scales) for l and for v.
    static double angular_filtered(int k, const Vec3& l, const Vec3& v,
                                   const std::vector<double>& light_scales,
                                   const std::vector<double>& view_scales);
    /// B at texel (x, y) for any directions.
    Color value(uint32_t x, uint32_t y, const Vec3& l, const Vec3& v) const;

private:
    uint32_t width_, height_;
};

/// BTF B: a Lambertian V-groove meso-structure (btf/vgroove.h) with grooves along the texture's
/// y, one period across its width, albedo `vgroove_albedo` per channel: texel (x, y) holds the
/// exact mean of the groove's reflectance factor over column x; the coarsest filtered level
/// (the mean of all texels) is the V-cavity's closed-form period average.
enum class Kind { Harmonic, VGroove };

struct Options {
    Kind kind = Kind::Harmonic;
    Format format = Format::Bdi;
    uint32_t width = 16, height = 16;
    std::vector<Vec3> directions;     ///< used for both lights and views
    int32_t color_model = kColorRgb;  ///< DFMF only: 0 or 11
    bool half = false;                ///< DFMF/FMF matrices as half floats (BDI always are)
    bool cosine_flag = false;         ///< store B cos(theta_l) and set the file's flag
    double vgroove_slope_deg = 35;    ///< BTF B: facet slope angle
    Color vgroove_albedo = Color(0.8f, 0.6f, 0.4f);
};

/// The header a synthetic BTF file gets.
Header header(const Options& options);
/// The reflectance factor the file written with `options` holds at texel (x, y), sampled light
/// l and view v, before any storage rounding.
Color reference_value(const Options& options, uint32_t x, uint32_t y, uint32_t l, uint32_t v);
/// Writes the synthetic BTF; throws SceneError when the file cannot be written and
/// std::invalid_argument for unsupported option combinations.
void write(const std::string& path, const Options& options);

}  // namespace femto::btf::synth
