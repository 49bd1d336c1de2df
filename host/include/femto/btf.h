// femto public API: bidirectional texture functions (BTFs) in the University of Bonn's binary
// formats (the BTF databases UBO2003 and UBO2014), read and written.
//
// A BTF B(x, y, l, v) stores, per texel (x, y) of a width x height texture, the appearance of a
// measured surface for every pair of a light direction l and a view direction v, each taken
// from the file's explicit direction sampling (81 directions in UBO2003, 151 in UBO2014). The
// directions are in the surface's local frame: z is the normal, x grows with the texel column
// (femto maps it to the texture's u), y completes a right-handed frame.
//
// femto decodes every format to the *reflectance factor*: pi times the apparent BRDF, so that a
// white Lambertian surface reads 1 for all l and v. Decoding follows the Bonn btflib: the
// colour model is undone (0: RGB; 11: log-luminance with chroma divided by luminance), then the
// dynamic-range reduction (FMF: exp(value) - 1e-5), then, when the file's cosine flag says the
// cosine of the light's polar angle is part of the data, that cosine is divided out.
//
// Formats: BDI (`!BDIF06R2!`, uncompressed half floats in chunks of scan lines; femto maps the
// file into memory rather than reading it, since measured BDIs are many gigabytes), DFMF
// (`!DFMF08FCR`, one truncated SVD per decorrelated colour channel) and FMF (`!FMF06FC`,
// `!FMF06FCR`, `!FMF12FCER`: one SVD over all channels). Every size in a header is checked
// against the file's length before anything is allocated: a corrupt or truncated file is a
// SceneError naming the file and the field.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "femto/color.h"
#include "femto/math.h"

namespace femto::btf {

enum class Format { Bdi, Dfmf, Fmf };
const char* format_name(Format format);

/// The colour models femto decodes (the Bonn numbering).
enum ColorModel : int32_t { kColorRgb = 0, kColorLogYuv = 11 };

/// Everything a BTF file says besides the reflectance values.
struct Header {
    Format format = Format::Bdi;
    uint32_t width = 0, height = 0;  ///< texels
    std::vector<Vec3> lights;        ///< sampled light directions (unit, local frame, z >= 0)
    std::vector<Vec3> views;         ///< sampled view directions
    bool cosine_flag = false;        ///< the data holds B * cos(theta_light)
    int32_t color_model = kColorRgb;
    uint32_t dynamic_range_method = 0;  ///< FMF: nonzero = the data is log(B + 1e-5)
    float ppmm = 0.f;                   ///< texels per millimetre (informative)
    std::string measurement_setup, image_sensor, light_source;  ///< informative strings

    size_t light_count() const { return lights.size(); }
    size_t view_count() const { return views.size(); }
};

/// A BTF in memory (compressed formats stay compressed: values are decoded on demand).
class Data {
public:
    virtual ~Data() = default;
    const Header& header() const { return header_; }
    /// The reflectance factor of texel (x, y) (x < width, y < height; row y = 0 is the file's
    /// first row) for sampled light `light` and sampled view `view`.
    virtual Color value(uint32_t x, uint32_t y, uint32_t light, uint32_t view) const = 0;
    /// Number of components kept per colour channel (compressed formats; 0 for BDI).
    virtual uint32_t components() const { return 0; }
    /// Bytes of memory the decoded representation holds (a mapped BDI counts as 0).
    virtual uint64_t memory_bytes() const = 0;

protected:
    explicit Data(Header header) : header_(std::move(header)) {}
    /// Turns raw decoded channels into the reflectance factor (colour model, dynamic range,
    /// cosine), as described at the top of this file.
    Color finish(const float raw[3], uint32_t light) const;
    Header header_;
};

/// The four texels around texture position uv on a width x height texture that tiles (uv (0, 0)
/// is the bottom-left corner and texel row 0 the top, as for `bitmap`), with their bilinear
/// weights: corner i is (x[i & 1], y[i >> 1]) with weight weight[i].
struct BilinearTexels {
    uint32_t x[2], y[2];
    float weight[4];
};
BilinearTexels bilinear_texels(Vec2 uv, uint32_t width, uint32_t height);

/// Reads a BTF file; throws SceneError ("FILE: FIELD: what is wrong") for anything it cannot
/// read. Reading never allocates more than the file's size implies.
std::shared_ptr<const Data> read(const std::string& path);

// ---- writing (femto btf synth, tests, conversions) ----------------------------------------

/// A matrix factorization M = U * SxV^T of `rows` x `cols`, `components` columns each,
/// stored row-major (U is rows x components, SxV is cols x components).
struct Factorization {
    uint32_t rows = 0, cols = 0, components = 0;
    std::vector<float> u, sxv;
};

/// Writes a BDI: `values` holds width x height x lights x views x 3 raw channel values, the
/// channel varying fastest, then the light, the view, x and y (the file's order), stored as
/// half floats. The header's format is ignored.
void write_bdi(const std::string& path, const Header& header, const std::vector<float>& values);
/// Writes a DFMF with one factorization per colour channel, rows = lights x views (light
/// fastest) and cols = width x height (y fastest), as the Bonn files store them. `half`
/// stores half floats (as the database does), else 32-bit floats.
void write_dfmf(const std::string& path, const Header& header,
                const std::array<Factorization, 3>& channels, bool half);
/// Writes an FMF (`!FMF06FCR`): rows = 3 x lights x views (channel fastest), cols = width x
/// height (y fastest).
void write_fmf(const std::string& path, const Header& header, const Factorization& matrix,
               bool half);

/// UBO2003's 81 directions (inclinations 0..75 degrees in steps of 15, 1/6/12/18/20/24 per
/// ring) and UBO2014's 151 (the Bonn dome's rings), in the local frame.
std::vector<Vec3> ubo2003_directions();
std::vector<Vec3> ubo2014_directions();

}  // namespace femto::btf
