// femto public API (libfemto_io): image output shared by the film plugins. Every write goes
// to a temporary file in the destination folder and is renamed into place, so a reader never
// sees a half-written file.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace femto::io {

/// A string attribute stored in EXR headers (e.g. {"femto:samples", "64"}).
using Attributes = std::vector<std::pair<std::string, std::string>>;

/// Writes an RGB float image (row-major, top row first) as a single-part OpenEXR file. With
/// `depth` ([height][width] floats) the file has a fourth float channel Z holding it (the
/// streak film's per-pixel sensor distance, femto/viz.h write_streak_exr).
void write_exr_rgb(const std::string& path, int width, int height, const float* rgb,
                   const Attributes& attributes, const float* depth = nullptr);
/// Tone-maps linear RGB through the OpenColorIO display transform (linear -> sRGB) of the
/// config shipped with femto and writes an 8-bit PNG. `exposure` is in stops.
void write_png_preview(const std::string& path, int width, int height, const float* rgb,
                       float exposure = 0.f);
/// Reads an RGB(A) image through OpenImageIO as linear float RGB; throws SceneError.
std::vector<float> read_image_rgb(const std::string& path, int& width, int& height,
                                  bool srgb_to_linear_if_8bit = true);

/// A time-resolved image (x-y-t cube): `data` is float32 laid out [height][width][bins][3],
/// the layout of the .npy files femto writes. `depth` (optional, [height][width]) is the mean
/// distance from the sensor to the first surface per pixel (-1 where nothing was hit).
struct Cube {
    int width = 0, height = 0, bins = 0;
    std::vector<float> data;
    std::vector<float> depth;
    Attributes attributes;
    const std::string* attribute(const std::string& name) const;
};

/// Writes a cube as a multi-part OpenEXR file: one RGB part per time bin (named t00000, ...),
/// plus a part "depth" (channel Z) when `depth` is given. Every part carries `attributes`.
/// With `pixel_scale` ([height][width]) every value is multiplied by its pixel's scale while
/// streaming, one part at a time, so a film can normalise without a second copy of its cube.
void write_exr_cube(const std::string& path, int width, int height, int bins, const float* data,
                    const float* depth, const Attributes& attributes,
                    const float* pixel_scale = nullptr);
/// Reads what write_exr_cube wrote; throws SceneError for other files.
Cube read_exr_cube(const std::string& path);
/// Writes a float32 NumPy .npy file of the given shape (C order).
/// With `pixel_scale`, the leading two dimensions are pixels: each pixel's values are scaled.
void write_npy(const std::string& path, const std::vector<size_t>& shape, const float* data,
               const float* pixel_scale = nullptr);
/// Reads a float32 .npy file; returns the data and sets `shape`.
std::vector<float> read_npy(const std::string& path, std::vector<size_t>& shape);

/// Path of the OpenColorIO config in use ($FEMTO_OCIO_CONFIG, else the one shipped).
std::string ocio_config_path();

}  // namespace femto::io
