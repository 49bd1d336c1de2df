// Internal (libfemto_io): what libfemto_io asks of OpenImageIO, kept in a module of its own
// (libfemto_oiio.so) that libfemto_io loads the first time it is needed.
//
// Why: Debian's OpenImageIO pulls about 260 shared libraries into the process (DICOM, HEIF,
// camera raw, OpenCV, ...), which costs ~0.4 s at every process start, while a render only writes
// EXR (OpenEXR) and PNG (libpng) files, and reads RGB EXR textures through OpenEXR too. Reading
// images of other formats (textures and environment maps) and writing animated GIFs (`femto viz
// frames --gif`) go through OpenImageIO; only processes that do so load it.
// docs/design-notes.md has the measurements.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace femto::io::detail {

/// An image decoded to float, all of its channels interleaved.
struct DecodedImage {
    int width = 0, height = 0, channels = 0;
    bool integer_8_or_16 = false;  // stored as 8- or 16-bit integers (sRGB-encoded, usually)
    // width x height x channels values. Not a std::vector, which would zero them first: a
    // corrupt 131-byte WebP declaring 7425 x 13429 pixels had 1.6 GB zeroed (7 s, 2 GB resident)
    // before its decoding failed; left uninitialised, the pages are touched only as pixels are
    // decoded into them.
    std::unique_ptr<float[]> pixels;
};

/// The module's functions. Each returns "" on success, or what went wrong (one line).
struct OiioModule {
    int version;  // kOiioModuleVersion: a module of another version of this interface is refused
    /// Reads `path` (any format OpenImageIO reads); images of more than `max_pixels` pixels
    /// are refused before their pixels are read.
    std::string (*decode)(const std::string& path, int64_t max_pixels, DecodedImage& out);
    /// Writes an animated, looping GIF of 8-bit RGB frames (width x height x 3 bytes each).
    std::string (*write_gif)(const std::string& path, int width, int height,
                             const std::vector<std::vector<unsigned char>>& frames, int fps);
};
inline constexpr int kOiioModuleVersion = 2;

/// The module's entry point, exported by libfemto_oiio.so.
#define FEMTO_OIIO_ENTRY "femto_oiio_module"
using OiioModuleEntry = const OiioModule* (*)();

/// Loads libfemto_oiio.so from libfemto_io's own folder on the first call; throws SceneError
/// naming the files tried when it cannot be loaded.
const OiioModule& oiio_module();

}  // namespace femto::io::detail
