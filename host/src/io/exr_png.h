// Internal (libfemto_io): EXR header attributes and PNG files, shared by image_io.cpp and
// viz.cpp.
#pragma once

#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>

#include <cstdint>
#include <initializer_list>
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

// A few kilobytes cut from an EXR declaring 2^28 pixels made a reader allocate 3 GB and decode
// for 10 s before failing. Readers therefore check, before allocating the image, that the
// offset table names every pixel block (isComplete(); kIncompleteExr says why not) and that the
// last block, which a truncated file lacks, reads (read_last_row()).
inline constexpr const char* kIncompleteExr =
    "it is incomplete: some of its pixel blocks are missing (a truncated or partly written "
    "file)";

/// Reads the last row of data window `dw` of `input` (an Imf::InputFile or Imf::InputPart)
/// into a row of scratch, each of `channels` in turn; throws what OpenEXR throws.
template <class ExrInput>
void read_last_row(ExrInput& input, const Imath::Box2i& dw,
                   std::initializer_list<const char*> channels) {
    const int64_t width = int64_t(dw.max.x) - dw.min.x + 1;
    std::vector<float> row(static_cast<size_t>(width));
    Imf::FrameBuffer fb;
    for (const char* c : channels)
        fb.insert(c, Imf::Slice::Make(Imf::FLOAT, row.data(), Imath::V2i(dw.min.x, dw.max.y), width,
                                      1, sizeof(float), sizeof(float) * size_t(width)));
    input.setFrameBuffer(fb);
    input.readPixels(dw.max.y, dw.max.y);
}

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
