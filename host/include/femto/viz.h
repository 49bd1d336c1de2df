// femto public API (libfemto_io): time-resolved outputs and the pictures `femto viz` makes from
// them (thesis ch. 4.3, 4.5, 4.6): the femto:* attributes every time-resolved file carries,
// frame tone mapping with one exposure for a whole cube, peak-time (isochrone) images,
// rainbow fusion, streak (x-t) slices and camera <-> world time unwarping (eq. 4.1).
//
// Cubes are femto::io::Cube: float32 [height][width][bins][3], optional depth [height][width]
// (distance from the sensor to the first surface, -1 where nothing was hit). A streak image
// (the x-t image of one row, see write_streak_exr) is handled as a cube of height 1.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "femto/color.h"
#include "femto/film.h"
#include "femto/image_io.h"
#include "femto/time.h"

namespace femto::io {

/// The femto:* header attributes every output carries: version, integrator, scene, seed,
/// samples (reached and requested), render time and whether the render was interrupted.
Attributes render_attributes(const RenderInfo& info);

/// The femto:* header attributes of a time-resolved output (render info, the time grid in
/// scene units and, when length_unit is known, picoseconds; its frame, camera or world time;
/// the temporal filter's type). Films append their own (e.g. femto:row) after these.
Attributes time_resolved_attributes(const TimeGrid& grid, const RenderInfo& info,
                                    const std::string& tfilter);

}  // namespace femto::io

namespace femto::viz {

/// Reads a cube written by a transient film: an OpenEXR cube (io::read_exr_cube), a streak
/// image (write_streak_exr; recognised by its femto:layout and femto:row attributes) as a cube
/// of height 1 with the depth from its channel Z, or a .npy of shape [H, W, T, C] (C = 1, 3
/// or 4; converted to RGB). Throws SceneError with a message naming the file for anything
/// else.
io::Cube load_cube(const std::string& path);
/// Whether the cube was read from a streak image (its femto:layout attribute): a cube of
/// height 1 whose row is the image's femto:row.
bool is_streak(const io::Cube& cube);
/// The cube's time grid: its bins, and start, bin width, length unit and frame from its femto:*
/// attributes, `start` / `bin_width` overriding theirs. Not `known` when the cube has neither
/// (e.g. a .npy) and they are not both given; the frame is Unknown without femto:time.
TimeGrid time_grid(const io::Cube& cube, std::optional<double> start = std::nullopt,
                   std::optional<double> bin_width = std::nullopt);

// ---- tone mapping --------------------------------------------------------------------------

enum class Tone { Linear, Log };
/// Parses "linear" / "log"; throws SceneError otherwise.
Tone parse_tone(const std::string& name);

/// The percentile of the reference level that pictures use by default (see reference_level).
inline constexpr double kLevelPercentile = 0.99;

/// Per pixel, 1 where the pixel sees an emitter directly, else 0. A pixel counts as an emitter
/// when more than half of its luminance arrives within one bin of the time at which light
/// emitted at t = 0 by the surface it sees would arrive: its depth in camera time, 0 in world
/// time. Light reflected by a surface arrives later by at least the surface's distance to a
/// light, so only emitters (and surfaces within a bin's length of one) qualify. All 0 when the
/// cube has no depth (a .npy) or no time axis or frame (femto:start, femto:bin_width,
/// femto:time). Assumes pulses shorter than a bin (the default delta pulse).
std::vector<uint8_t> emitter_pixels(const io::Cube& cube);

/// The reference level of a picture, the linear value shown as white (or, with the log tone,
/// as full brightness): the value at `percentile` (0..1) of the non-zero entries, ignoring the
/// pixels that see an emitter (emitter_pixels), so that a lamp in view does not set the level
/// and leave the scene black. Returns 1 when nothing is left.
/// For a cube: over the per-pixel, per-bin maximum RGB component, so that every frame of a
/// movie shares one level and frames are comparable.
float reference_level(const io::Cube& cube, double percentile = kLevelPercentile);
/// For one RGB image (row-major, 3 floats per pixel): over each pixel's largest component,
/// skipping the pixels whose entry in `excluded` (one per pixel, or empty) is non-zero.
float reference_level(const std::vector<float>& rgb, const std::vector<uint8_t>& excluded = {},
                      double percentile = kLevelPercentile);

/// Maps linear RGB to display values in [0, 1]: x = value * 2^exposure / reference;
/// Linear: the sRGB transfer curve of clamp(x); Log: log(1 + k x) / log(1 + k) with
/// k = kLogRange (a logarithmic transformation, ch. 4.5, showing ~3 decades below the
/// reference). The result is what an 8-bit file stores (times 255).
inline constexpr float kLogRange = 1000.f;
std::vector<float> tone_map(const float* rgb, size_t pixels, float reference, float exposure,
                            Tone tone);

/// Frame `bin` of the cube: an RGB image [height][width][3].
std::vector<float> frame(const io::Cube& cube, int bin);

// ---- pictures ------------------------------------------------------------------------------

/// A rainbow colour for u in [0, 1]: red (u = 0, early) through yellow, green, cyan to blue
/// (u = 1, late); a fully saturated hue whose largest component is 1.
Color time_colour(double u);

/// Per pixel, the bin of maximum radiance (of luminance), or -1 where the pixel is black.
std::vector<int> peak_bins(const io::Cube& cube);
/// Per pixel, the time of maximum radiance (bin centre, scene units); NaN where black.
std::vector<float> peak_times(const io::Cube& cube, const TimeGrid& grid);
/// The peak-time image (ch. 4.5): each pixel coloured by its peak time (time_colour over the
/// bins that hold peaks), with the brightness of its peak (the radiance within two bins of
/// the peak, log tone). With `isochrone_spacing` > 0, as in the thesis only every
/// `isochrone_spacing`-th bin contributes, so that coloured isochrones are separated by black.
/// The brightness is relative to `level` when given, else to reference_level of the peak
/// energies (emitters ignored), scaled by 2^exposure. Returns display values in [0, 1],
/// [height][width][3].
std::vector<float> peak_time_image(const io::Cube& cube, int isochrone_spacing = 0,
                                   std::optional<float> level = std::nullopt, float exposure = 0.f);

/// Rainbow fusion (ch. 4.5): the full fusion N_ij = sum_k M_ijk (w_k = 1) of the frames'
/// luminance, with each frame k tinted by the colour of its time, time_colour(k / (T - 1)).
/// Linear RGB [H][W][3].
std::vector<float> rainbow_fusion(const io::Cube& cube);

/// The x-t slice at row y (ch. 4.3): an image `width` wide and `bins` tall, time increasing
/// downward, [bins][width][3]. Throws SceneError when y is out of range.
std::vector<float> streak_slice(const io::Cube& cube, int y);

/// Time unwarping (eq. 4.1): shifts each pixel's time series by its depth z (t_world =
/// t_camera - z; eta = 1 as in the thesis' table-top scenes) to convert a camera-time cube to
/// world time (`to_world`) or back. Bins are resampled by linear interpolation of the shifted
/// piecewise-constant series, which conserves each pixel's energy; whole-bin shifts are exact.
/// The output keeps the input's bin width and grid alignment; with `keep_window` it keeps the
/// input's window too (energy shifted outside is dropped and reported in `dropped`), else the
/// window becomes the bins that hold energy after the shift (nothing is dropped). Attributes
/// femto:time, femto:start, femto:bins (and femto:start_ps) are updated and femto:unwarped is
/// set; the depth and the other attributes are kept, so a streak image (is_streak) stays one.
/// Throws SceneError when the cube has no depth, is already in that time, or has no time axis.
struct UnwarpResult {
    io::Cube cube;
    double dropped = 0.0;  ///< fraction of the total energy shifted outside (keep_window)
};
UnwarpResult unwarp(const io::Cube& cube, const TimeGrid& grid, bool to_world,
                    bool keep_window = false);

// ---- files ---------------------------------------------------------------------------------

/// Writes display values in [0, 1] (RGB, row-major) as an 8-bit PNG (atomically).
void write_png8(const std::string& path, int width, int height, const std::vector<float>& display);
/// Writes display frames (each width*height*3 values in [0, 1]) as a looping animated GIF at
/// `fps` frames per second, through OpenImageIO's multi-subimage GIF writer (atomically).
void write_gif(const std::string& path, int width, int height,
               const std::vector<std::vector<float>>& frames, int fps = 12);
/// Writes row `y` of the cube as a streak image, the format of the streak film (docs/viz.md):
/// a single-part OpenEXR file `width` wide and `bins` tall (x to the right, time increasing
/// downward) with float channels R, G, B and, when the cube has depth, Z: each pixel's depth
/// repeated down its column (every time row holds it). The header is `attributes`, which
/// should hold the time-resolved attributes and femto:row, plus femto:layout
/// ("streak image: x to the right, time downward"). Throws SceneError when y is out of range.
void write_streak_exr(const std::string& path, const io::Cube& cube, int y,
                      io::Attributes attributes);
/// Writes a single-channel float image (e.g. peak times) as OpenEXR (channel Y), atomically.
void write_exr_gray(const std::string& path, int width, int height, const float* values,
                    const io::Attributes& attributes);

}  // namespace femto::viz
