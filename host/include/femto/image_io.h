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

/// Writes an RGB float image (row-major, top row first) as a single-part OpenEXR file.
void write_exr_rgb(const std::string& path, int width, int height, const float* rgb,
                   const Attributes& attributes);
/// Tone-maps linear RGB through the OpenColorIO display transform (linear -> sRGB) of the
/// config shipped with femto and writes an 8-bit PNG. `exposure` is in stops.
void write_png_preview(const std::string& path, int width, int height, const float* rgb,
                       float exposure = 0.f);
/// Reads an RGB(A) image through OpenImageIO as linear float RGB; throws SceneError.
std::vector<float> read_image_rgb(const std::string& path, int& width, int& height,
                                  bool srgb_to_linear_if_8bit = true);

/// Path of the OpenColorIO config in use ($FEMTO_OCIO_CONFIG, else the one shipped).
std::string ocio_config_path();

}  // namespace femto::io
