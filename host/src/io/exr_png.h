// Internal (libfemto_io): EXR header attributes and PNG files, shared by image_io.cpp and
// viz.cpp.
#pragma once

#include <OpenEXR/ImfHeader.h>

#include <string>
#include <vector>

#include "femto/image_io.h"

namespace femto::io::detail {

/// Stores `value` typed where it reads as a number (int, or double), as text otherwise, so
/// that EXR tools show numbers and scripts need not parse text. Integers beyond int32 stay
/// text: a double would round them.
void insert_attribute(Imf::Header& header, const std::string& key, const std::string& value);
/// The header's text attributes and femto's numbers; not OpenEXR's own (pixelAspectRatio, ...),
/// which belong to the file's layout rather than to the render.
Attributes read_attributes(const Imf::Header& header);

/// One float channel of an image to write: pixel (x, y) at first[(y * width + x) * stride].
struct ExrChannel {
    std::string name;
    const float* first;
    size_t stride;
};
/// Writes `channels` (float, ZIP-compressed) and `attributes` (insert_attribute) as an EXR
/// file, atomically; throws SceneError.
void write_exr_channels(const std::string& path, int width, int height,
                        const std::vector<ExrChannel>& channels, const Attributes& attributes);

/// Display values in [0, 1] (others clamped, NaN black) as 8-bit values.
std::vector<unsigned char> display_bytes(const std::vector<float>& display);
/// Writes display values (3 a pixel, rows top first) as an 8-bit sRGB PNG file through libpng,
/// atomically; throws SceneError.
void write_png_display(const std::string& path, int width, int height,
                       const std::vector<float>& display);

}  // namespace femto::io::detail
