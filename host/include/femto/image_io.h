// femto public API (libfemto_io): image output shared by the film plugins. Every write goes
// to a temporary file in the destination folder and is renamed into place, so a reader never
// sees a half-written file; an OutputSet makes a render's files appear together.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace femto::io {

/// A string attribute stored in EXR headers (e.g. {"femto:samples", "64"}).
using Attributes = std::vector<std::pair<std::string, std::string>>;

/// Named float channels written beside R, G, B (integrator AOVs): channel `names[k]` of pixel
/// p (row-major, top row first) is `data[p * names.size() + k]`. A name "layer.C" puts channel
/// C in layer "layer", as OpenEXR tools group them.
struct ExtraChannels {
    std::vector<std::string> names;
    const float* data = nullptr;
};

/// Writes an RGB float image (row-major, top row first) as a single-part OpenEXR file. With
/// `depth` ([height][width] floats) the file has a fourth float channel Z holding it (the
/// streak film's per-pixel sensor distance, femto/viz.h write_streak_exr); `extra` adds named
/// channels (an error when one is named R, G, B or Z, or twice).
void write_exr_rgb(const std::string& path, int width, int height, const float* rgb,
                   const Attributes& attributes, const float* depth = nullptr,
                   const ExtraChannels& extra = {});
/// Tone-maps linear RGB through the OpenColorIO display transform (linear -> sRGB) of the
/// config shipped with femto and writes an 8-bit PNG. `exposure` is in stops.
void write_png_preview(const std::string& path, int width, int height, const float* rgb,
                       float exposure = 0.f);
/// Reads an image as linear float RGB (a one-channel image as grey): EXR files with R, G and B
/// channels through OpenEXR, any other file through OpenImageIO (loaded on first use); throws
/// SceneError.
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

/// How write_exr_cube stores the cube: the OpenEXR compression and OpenEXR's own thread pool.
/// The defaults are what bench/write.cpp measured fastest for transient cubes (docs/outputs.md).
struct ExrCubeOptions {
    enum class Compression { none, rle, zips, zip, piz };
    Compression compression = Compression::rle;
    int zip_level = 1;  ///< 1 (fastest) ... 9 (smallest), for zips and zip
    int threads = 0;    ///< OpenEXR's thread pool: 0 = one per core, 1 = write on this thread
};
/// Parses "none", "rle", "zips", "zip" or "piz"; false for anything else.
bool parse_exr_compression(const std::string& name, ExrCubeOptions::Compression& out);

/// Writes a cube as an OpenEXR file with two parts. Part "frames" is the film's frames stacked
/// top to bottom: a tiled RGB float image `width` wide and `height * bins` tall whose rows
/// [t * height, (t + 1) * height) are time bin t (any EXR tool reads a frame as a crop, e.g.
/// `oiiotool cube.exr --cut WxH+0+{t*H}`). Part "depth" (channel Z) holds `depth` when given.
/// `attributes` go into the frames part; values that read as numbers are stored as int or
/// double attributes. With `pixel_scale` ([height][width]) every value is multiplied by its
/// pixel's scale. The cube is transposed a batch of rows at a time: writing allocates at most
/// about 1/16 of the cube (or 8 MB) beyond it, whatever the number of bins.
void write_exr_cube(const std::string& path, int width, int height, int bins, const float* data,
                    const float* depth, const Attributes& attributes,
                    const float* pixel_scale = nullptr, const ExrCubeOptions& options = {});
/// Reads what write_exr_cube wrote (also the older layout with one part per bin, named
/// t00000, ...); throws SceneError for other files.
Cube read_exr_cube(const std::string& path);
/// Writes a float32 NumPy .npy file of the given shape (C order).
/// With `pixel_scale`, the leading two dimensions are pixels: each pixel's values are scaled.
void write_npy(const std::string& path, const std::vector<size_t>& shape, const float* data,
               const float* pixel_scale = nullptr);
/// Writes a float32 .npy file whose leading two dimensions are pixels, one pixel at a time:
/// fill_pixel(p, out) writes pixel p's values (the product of shape[2...]) to out. For outputs
/// computed from the film's sums, so that no second cube is ever allocated.
void write_npy_pixels(const std::string& path, const std::vector<size_t>& shape,
                      const std::function<void(size_t pixel, float* out)>& fill_pixel);
/// Reads a float32 .npy file; returns the data and sets `shape`.
std::vector<float> read_npy(const std::string& path, std::vector<size_t>& shape);

namespace detail {
struct OutputSetAccess;
}

/// A render's output files, made visible together. While a set is alive, the files added to it
/// and written (by any writer here, on this thread) stay under their hidden temporary names;
/// commit() then renames them all into place:
///
///     io::OutputSet files;
///     io::write_exr_rgb(files.add(base + ".exr"), ...);
///     io::write_png_preview(files.add(base + ".png"), ...);
///     return files.commit();
///
/// Until commit() the previous outputs stay untouched, and the files of a set that is never
/// committed (an error while writing one of them) are removed, so a failed write never leaves a
/// new EXR beside an old .npy. If a rename fails, the error names the files already replaced.
class OutputSet {
public:
    OutputSet();
    OutputSet(const OutputSet&) = delete;
    OutputSet& operator=(const OutputSet&) = delete;
    ~OutputSet();
    /// Makes `path` part of the set; returns it (to hand to a writer).
    std::string add(const std::string& path);
    /// Renames every file into place; returns the final paths in the order they were added.
    std::vector<std::string> commit();

private:
    friend struct detail::OutputSetAccess;
    bool hold(const std::string& tmp, const std::string& path);
    void close();
    std::vector<std::pair<std::string, std::string>> files_;  // {temporary, final}
    bool open_ = true;
};

/// Path of the OpenColorIO config in use ($FEMTO_OCIO_CONFIG, else the one shipped).
std::string ocio_config_path();

}  // namespace femto::io
