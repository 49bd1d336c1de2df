// Internal (libfemto_io): EXR header attributes and PNG files, shared by image_io.cpp and
// viz.cpp.
#pragma once

#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>

#include <cstdint>
#include <initializer_list>
#include <stdexcept>
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

/// Empty when every attribute the EXR file's header (or headers, multi-part) holds fits in the
/// file; else why not. OpenEXR 3.1 allocates a text, vector, preview or unknown attribute's
/// declared size before reading it, so a 300-byte file declaring a 2 GB attribute cost 2 GB
/// (the EXR fuzzer ran at 10 inputs a second). The header is walked as OpenEXR walks it:
/// attributes of a fixed-size type by their type's size, a channel list to its end. Also not
/// empty when a header's pixel blocks (tiles, or a compression's group of scanlines) would
/// each take over 256 MiB to decode: OpenEXR allocates such a buffer per thread on opening
/// the file. Anything else odd is left for OpenEXR to report, with femto's limits on widths
/// set first (the process-wide Imf::Header::setMaxImageSize and setMaxTileSize).
std::string exr_header_problem(const std::string& path);

/// Throws std::runtime_error unless `input` (any OpenEXR input file or part) has an offset
/// table that names every pixel block (isComplete()): the first test of require_whole_exr()
/// and of the cube reader's tiled check.
template <class ExrInput>
void require_complete(ExrInput& input) {
    if (!input.isComplete())
        throw std::runtime_error(
            "it is incomplete: some of its pixel blocks are missing (a truncated or partly "
            "written file)");
}

/// Throws std::runtime_error unless `input` (an Imf::InputFile or Imf::InputPart) looks whole:
/// its offset table names every pixel block (isComplete()) and the first and last rows of its
/// data window `dw` read, each of `channels` into a row of scratch. A cut file lacks the blocks
/// at its end, which hold one of those rows whether its lines run down or up. Readers call it
/// before allocating the image: a few kilobytes cut from a file declaring 2^28 pixels made
/// one allocate 3 GB and decode for 10 s before failing.
template <class ExrInput>
void require_whole_exr(ExrInput& input, const Imath::Box2i& dw,
                       std::initializer_list<const char*> channels) {
    require_complete(input);
    const int64_t width = int64_t(dw.max.x) - dw.min.x + 1;
    std::vector<float> row(static_cast<size_t>(width));
    for (const int y : {dw.min.y, dw.max.y}) {
        Imf::FrameBuffer fb;
        for (const char* c : channels)
            fb.insert(c, Imf::Slice::Make(Imf::FLOAT, row.data(), Imath::V2i(dw.min.x, y), width, 1,
                                          sizeof(float), sizeof(float) * size_t(width)));
        input.setFrameBuffer(fb);
        input.readPixels(y, y);
    }
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
