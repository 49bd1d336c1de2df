// Internal (libfemto_io): EXR header attributes and PNG files, shared by image_io.cpp and
// viz.cpp.
#pragma once

#include <OpenEXR/ImfHeader.h>

#include <string>

#include "femto/image_io.h"

namespace femto::io::detail {

/// Stores `value` typed where it reads as a number (int, or double), as text otherwise, so
/// that EXR tools show numbers and scripts need not parse text. Integers beyond int32 stay
/// text: a double would round them.
void insert_attribute(Imf::Header& header, const std::string& key, const std::string& value);
/// The header's text attributes and femto's numbers; not OpenEXR's own (pixelAspectRatio, ...),
/// which belong to the file's layout rather than to the render.
Attributes read_attributes(const Imf::Header& header);

/// Writes 8-bit sRGB pixels (rows top first, 3 bytes a pixel) as a PNG file through libpng;
/// returns "" or what went wrong.
std::string write_png_rgb8(const std::string& path, int width, int height,
                           const unsigned char* rgb);

}  // namespace femto::io::detail
