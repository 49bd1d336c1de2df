// Time-resolved outputs and the pictures of `femto viz` (femto/viz.h; thesis ch. 4.3-4.6).
#include "femto/viz.h"

#include <OpenColorIO/OpenColorIO.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>

#include "femto/error.h"
#include "femto/input_file.h"
#include "femto/memory.h"
#include "io/atomic_file.h"
#include "io/display.h"
#include "io/exr_png.h"
#include "io/oiio_module.h"
#include "util/files.h"

namespace fs = std::filesystem;
namespace OCIO = OCIO_NAMESPACE;

namespace femto::io {

Attributes render_attributes(const RenderInfo& info) {
    Attributes attrs = {
        {"femto:version", info.femto_version},
        {"femto:integrator", info.integrator},
        {"femto:scene", info.scene_file},
        {"femto:seed", std::to_string(info.seed)},
        {"femto:samples", std::to_string(info.samples_per_pixel)},
        {"femto:samples_requested", std::to_string(info.samples_requested)},
        {"femto:render_seconds", fmt::format("{:.3f}", info.render_seconds)},
        {"femto:interrupted", info.interrupted ? "true" : "false"},
        {"femto:rejected_nan", std::to_string(info.rejected.nan)},
        {"femto:rejected_infinite", std::to_string(info.rejected.infinite)},
        {"femto:rejected_negative", std::to_string(info.rejected.negative)},
    };
    if (info.processes > 1) attrs.push_back({"femto:processes", std::to_string(info.processes)});
    return attrs;
}

Attributes time_resolved_attributes(const TimeGrid& grid, const RenderInfo& info,
                                    const std::string& tfilter) {
    Attributes attrs = render_attributes(info);
    const Attributes time = {
        {"femto:start", fmt::format("{}", grid.start)},
        {"femto:bin_width", fmt::format("{}", grid.bin_width)},
        {"femto:bins", std::to_string(grid.bins)},
        {"femto:units", "optical path length in scene units (time x c)"},
        {"femto:length_unit", grid.length_unit},
        {"femto:time", time_frame_name(grid.frame)},
        {"femto:tfilter", tfilter},
    };
    attrs.insert(attrs.end(), time.begin(), time.end());
    if (grid.metres_per_unit() > 0) {
        attrs.push_back({"femto:start_ps", fmt::format("{}", grid.to_picoseconds(grid.start))});
        attrs.push_back(
            {"femto:bin_width_ps", fmt::format("{}", grid.to_picoseconds(grid.bin_width))});
    }
    return attrs;
}

}  // namespace femto::io

namespace femto::viz {

namespace {

using io::detail::temp_path_for;
void commit(const std::string& tmp, const std::string& path) { io::detail::commit_file(tmp, path); }

[[noreturn]] void fail_write(const std::string& tmp, const std::string& path,
                             const std::string& err) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw SceneError(fmt::format("cannot write \"{}\": {}", path, err));
}

const float* px(const io::Cube& c, int x, int y, int t) {
    return &c.data[((size_t(y) * size_t(c.width) + size_t(x)) * size_t(c.bins) + size_t(t)) * 3];
}

float lum(const float* v) { return Color{v[0], v[1], v[2]}.luminance(); }

bool parse_double(const std::string& s, double& out) {
    try {
        size_t used = 0;
        out = std::stod(s, &used);
        return used == s.size() && std::isfinite(out);
    } catch (const std::exception&) {
        return false;
    }
}

void set_attribute(io::Attributes& attrs, const std::string& name, const std::string& value) {
    for (auto& [k, v] : attrs)
        if (k == name) {
            v = value;
            return;
        }
    attrs.emplace_back(name, value);
}

// The value at `percentile` of `values`; 1 when there are none or it is not positive.
float percentile_of(std::vector<float> values, double percentile) {
    if (values.empty()) return 1.f;
    const size_t k = std::min(values.size() - 1, size_t(double(values.size() - 1) * percentile));
    std::nth_element(values.begin(), values.begin() + ptrdiff_t(k), values.end());
    return values[k] > 0 ? values[k] : 1.f;
}

// The value at `percentile` of the positive, finite values[p] whose excluded[p] is 0 (every
// value when `excluded` is empty); 1 when there are none.
float level_of(const std::vector<float>& values, const std::vector<uint8_t>& excluded,
               double percentile) {
    std::vector<float> kept;
    for (size_t p = 0; p < values.size(); ++p)
        if (values[p] > 0 && std::isfinite(values[p]) && (excluded.empty() || !excluded[p]))
            kept.push_back(values[p]);
    return percentile_of(std::move(kept), percentile);
}

constexpr double kPeakColourPercentile = 0.01;

constexpr const char* kStreakLayout = "streak image: x to the right, time downward";

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

// A streak image (write_streak_exr) as a cube of height 1; nullopt when the file's header does
// not mark it as one (a cube, a steady image: read_exr_cube then names the problem), or is not
// a single-part EXR that OpenEXR opens (read_exr_cube reports that too).
std::optional<io::Cube> read_streak(const std::string& path) {
    if (!io::detail::exr_header_problem(path).empty()) return std::nullopt;  // read_exr_cube says
    std::unique_ptr<Imf::InputFile> file;
    try {
        file = std::make_unique<Imf::InputFile>(path.c_str());
    } catch (const std::exception&) {
        return std::nullopt;
    }
    const Imf::Header& header = file->header();
    const auto* layout = header.findTypedAttribute<Imf::StringAttribute>("femto:layout");
    if (!layout || !starts_with(layout->value(), "streak image") ||
        header.find("femto:row") == header.end())
        return std::nullopt;
    const Imath::Box2i dw = header.dataWindow();
    const int64_t W = int64_t(dw.max.x) - dw.min.x + 1, T = int64_t(dw.max.y) - dw.min.y + 1;
    if (W <= 0 || T <= 0 || W * T > (int64_t(1) << 28))
        throw SceneError(
            fmt::format("streak image \"{}\" has an unsupported size {}x{}", path, W, T));
    const Imf::ChannelList& channels = header.channels();
    for (const char* c : {"R", "G", "B"})
        if (!channels.findChannel(c))
            throw SceneError(fmt::format("streak image \"{}\" has no channels R, G and B", path));
    try {
        io::detail::require_whole_exr(*file, dw, {"R", "G", "B"});
    } catch (const std::exception& e) {
        throw SceneError(fmt::format("cannot read streak image \"{}\": {}", path, e.what()));
    }
    const bool has_depth = channels.findChannel("Z") != nullptr;
    const size_t n = size_t(W) * size_t(T);
    std::vector<float> planes((has_depth ? 4 : 3) * n);  // R, G, B (and Z) planes, rows of W
    Imf::FrameBuffer fb;
    const char* names[4] = {"R", "G", "B", "Z"};
    for (size_t k = 0; k < (has_depth ? 4u : 3u); ++k)  // each plane starts at the window's origin
        fb.insert(names[k], Imf::Slice::Make(Imf::FLOAT, planes.data() + k * n, dw.min, W, T,
                                             sizeof(float), sizeof(float) * size_t(W)));
    try {
        file->setFrameBuffer(fb);
        file->readPixels(dw.min.y, dw.max.y);
    } catch (const std::exception& e) {
        throw SceneError(fmt::format("cannot read streak image \"{}\": {}", path, e.what()));
    }
    io::Cube cube;
    cube.width = int(W);
    cube.height = 1;
    cube.bins = int(T);
    cube.data.resize(n * 3);
    for (size_t t = 0; t < size_t(T); ++t)
        for (size_t x = 0; x < size_t(W); ++x)
            for (size_t c = 0; c < 3; ++c)
                cube.data[(x * size_t(T) + t) * 3 + c] = planes[c * n + t * size_t(W) + x];
    if (has_depth)  // every time row holds the depth: take the first
        cube.depth.assign(planes.begin() + std::ptrdiff_t(3 * n),
                          planes.begin() + std::ptrdiff_t(3 * n) + W);
    for (auto& attribute : io::detail::read_attributes(header))
        if (starts_with(attribute.first, "femto:")) cube.attributes.push_back(std::move(attribute));
    return cube;
}

}  // namespace

bool is_streak(const io::Cube& cube) {
    const std::string* layout = cube.attribute("femto:layout");
    return cube.height == 1 && layout && starts_with(*layout, "streak image");
}

io::Cube load_cube(const std::string& path) {
    std::error_code ec;
    if (!femto::detail::entry_exists(path))
        throw SceneError(fmt::format("\"{}\" does not exist", path));
    if (fs::is_directory(path, ec))
        throw SceneError(fmt::format("\"{}\" is a folder, not a cube file", path));
    char magic[8] = {};
    // A FIFO would block here (and in the readers below) forever: InputFile refuses it.
    InputFile(path, SourceLocation{}).read(magic, 8);
    // By its magic number, or, for a file named .npy, as one (whose reader says what is wrong).
    if (std::string(magic, 6) != "\x93NUMPY" && fs::path(path).extension() != ".npy") {
        // A single-part OpenEXR file (the version field's multi-part bit, 0x1000, is clear)
        // may be a streak image; a cube has a frames part and (usually) a depth part.
        const bool single_part_exr =
            std::string(magic, 4) == "\x76\x2f\x31\x01" && (uint8_t(magic[5]) & 0x10) == 0;
        if (single_part_exr)
            if (std::optional<io::Cube> streak = read_streak(path)) return std::move(*streak);
        return io::read_exr_cube(path);
    }
    std::vector<size_t> shape;
    std::vector<float> data = io::read_npy(path, shape);
    if (shape.size() != 4 || !(shape[3] == 1 || shape[3] == 3 || shape[3] == 4))
        throw SceneError(fmt::format(
            "\"{}\": expected a cube of shape [height, width, bins, channels] with 1, 3 or 4 "
            "channels",
            path));
    if (shape[0] > (1u << 20) || shape[1] > (1u << 20) || shape[2] > (1u << 20))
        throw SceneError(fmt::format("\"{}\": the cube is too large", path));
    io::Cube cube;
    cube.height = int(shape[0]);
    cube.width = int(shape[1]);
    cube.bins = int(shape[2]);
    const size_t C = shape[3], n = shape[0] * shape[1] * shape[2];
    if (C == 3) {
        cube.data = std::move(data);
    } else {
        cube.data.resize(n * 3);
        for (size_t i = 0; i < n; ++i)
            for (size_t c = 0; c < 3; ++c) cube.data[3 * i + c] = data[i * C + (C == 1 ? 0 : c)];
    }
    return cube;
}

TimeGrid time_grid(const io::Cube& cube, std::optional<double> start,
                   std::optional<double> bin_width) {
    TimeGrid grid;
    grid.bins = cube.bins;
    double s = 0, w = 0;
    const std::string* as = cube.attribute("femto:start");
    const std::string* aw = cube.attribute("femto:bin_width");
    const bool have = as && aw && parse_double(*as, s) && parse_double(*aw, w) && w > 0;
    if (have) {
        grid.start = s;
        grid.bin_width = w;
    }
    if (start) grid.start = *start;
    if (bin_width) {
        if (!(*bin_width > 0) || !std::isfinite(*bin_width))
            throw SceneError(fmt::format("--bin-width must be > 0, got {}", *bin_width));
        grid.bin_width = *bin_width;
    }
    grid.known = have || (start && bin_width);
    if (const std::string* u = cube.attribute("femto:length_unit")) grid.length_unit = *u;
    const std::string* t = cube.attribute("femto:time");
    grid.frame = t ? parse_time_frame(*t) : TimeFrame::Unknown;
    return grid;
}

Tone parse_tone(const std::string& name) {
    if (name == "linear") return Tone::Linear;
    if (name == "log") return Tone::Log;
    throw SceneError(fmt::format("unknown tone curve \"{}\" (valid: linear, log)", name));
}

std::vector<uint8_t> emitter_pixels(const io::Cube& cube) {
    const size_t pixels = size_t(cube.width) * size_t(cube.height), T = size_t(cube.bins);
    std::vector<uint8_t> emitter(pixels, 0);
    const TimeGrid grid = time_grid(cube);
    if (cube.depth.size() != pixels || !grid.known || grid.frame == TimeFrame::Unknown)
        return emitter;
    for (size_t p = 0; p < pixels; ++p) {
        const float depth = cube.depth[p];
        if (!(depth > 0) || !std::isfinite(depth)) continue;  // the pixel saw nothing
        // When light the seen surface emitted at t = 0 reaches the sensor.
        const double t = grid.frame == TimeFrame::World ? 0.0 : double(depth);
        const double bin = std::floor((t - grid.start) / grid.bin_width);
        if (!(bin >= -1.0 && bin <= double(T))) continue;  // outside the window
        double near = 0, total = 0;
        for (size_t k = 0; k < T; ++k) {
            const double l = lum(&cube.data[(p * T + k) * 3]);
            total += l;
            if (std::abs(double(k) - bin) <= 1.0) near += l;
        }
        emitter[p] = total > 0 && near > 0.5 * total;
    }
    return emitter;
}

float reference_level(const io::Cube& cube, double percentile) {
    const std::vector<uint8_t> emitter = emitter_pixels(cube);
    const size_t n = cube.data.size() / 3, T = size_t(std::max(1, cube.bins));
    const size_t stride = std::max<size_t>(1, n / (size_t(1) << 22));
    std::vector<float> values;
    for (size_t i = 0; i < n; i += stride) {
        if (emitter[i / T]) continue;
        const float* v = &cube.data[3 * i];
        const float m = std::max({v[0], v[1], v[2]});
        if (m > 0 && std::isfinite(m)) values.push_back(m);
    }
    return percentile_of(std::move(values), percentile);
}

float reference_level(const std::vector<float>& rgb, const std::vector<uint8_t>& excluded,
                      double percentile) {
    std::vector<float> largest(rgb.size() / 3);
    for (size_t p = 0; p < largest.size(); ++p)
        largest[p] = std::max({rgb[3 * p], rgb[3 * p + 1], rgb[3 * p + 2]});
    return level_of(largest, excluded, percentile);
}

std::vector<float> tone_map(const float* rgb, size_t pixels, float reference, float exposure,
                            Tone tone) {
    const float scale = std::exp2(exposure) / (reference > 0 ? reference : 1.f);
    std::vector<float> out(rgb, rgb + 3 * pixels);
    for (float& v : out) v = std::isfinite(v) ? std::max(0.f, v * scale) : 0.f;
    if (tone == Tone::Log) {
        const float norm = 1.f / std::log1p(kLogRange);
        for (float& v : out) v = std::min(1.f, std::log1p(kLogRange * v) * norm);
    } else {
        for (float& v : out) v = std::min(1.f, v);
        OCIO::PackedImageDesc desc(out.data(), long(pixels), 1, 3);
        io::detail::display_processor()->apply(desc);
        for (float& v : out) v = std::clamp(v, 0.f, 1.f);
    }
    return out;
}

std::vector<float> frame(const io::Cube& cube, int bin) {
    if (bin < 0 || bin >= cube.bins)
        throw SceneError(fmt::format("bin {} is out of range [0, {})", bin, cube.bins));
    std::vector<float> out(size_t(cube.width) * size_t(cube.height) * 3);
    for (int y = 0; y < cube.height; ++y)
        for (int x = 0; x < cube.width; ++x) {
            const float* v = px(cube, x, y, bin);
            float* o = &out[(size_t(y) * size_t(cube.width) + size_t(x)) * 3];
            o[0] = v[0];
            o[1] = v[1];
            o[2] = v[2];
        }
    return out;
}

Color time_colour(double u) {
    // HSV hue from 0 (red) to 240 degrees (blue), full saturation and value.
    const double h = std::clamp(u, 0.0, 1.0) * 4.0;  // in sextants of 60 degrees
    const int i = std::min(3, int(h));
    const float f = float(h - i);
    switch (i) {
        case 0:
            return {1.f, f, 0.f};  // red -> yellow
        case 1:
            return {1.f - f, 1.f, 0.f};  // yellow -> green
        case 2:
            return {0.f, 1.f, f};  // green -> cyan
        default:
            return {0.f, 1.f - f, 1.f};  // cyan -> blue
    }
}

std::vector<int> peak_bins(const io::Cube& cube) {
    std::vector<int> peaks(size_t(cube.width) * size_t(cube.height), -1);
    for (int y = 0; y < cube.height; ++y)
        for (int x = 0; x < cube.width; ++x) {
            float best = 0;
            int arg = -1;
            for (int t = 0; t < cube.bins; ++t) {
                const float l = lum(px(cube, x, y, t));
                if (l > best) {
                    best = l;
                    arg = t;
                }
            }
            peaks[size_t(y) * size_t(cube.width) + size_t(x)] = arg;
        }
    return peaks;
}

std::vector<float> peak_times(const io::Cube& cube, const TimeGrid& grid) {
    const std::vector<int> peaks = peak_bins(cube);
    std::vector<float> times(peaks.size());
    for (size_t i = 0; i < peaks.size(); ++i)
        times[i] = peaks[i] < 0 ? std::numeric_limits<float>::quiet_NaN()
                                : float(grid.bin_centre(peaks[i]));
    return times;
}

namespace {

// The peak bins that the rainbow spans, red to blue: the 1st to 99th percentile of the peaks
// of the pixels that do not see an emitter (every lit pixel when all do), so that neither a
// lamp's early peak nor a few noisy late ones squeeze the scene into a couple of hues.
std::pair<int, int> peak_colour_range(const std::vector<int>& peaks,
                                      const std::vector<uint8_t>& emitter) {
    std::vector<int> lit;
    for (size_t p = 0; p < peaks.size(); ++p)
        if (peaks[p] >= 0 && !emitter[p]) lit.push_back(peaks[p]);
    if (lit.empty())
        for (int k : peaks)
            if (k >= 0) lit.push_back(k);
    if (lit.empty()) return {0, 0};
    std::sort(lit.begin(), lit.end());
    const auto at = [&](double q) { return lit[size_t(std::lround(q * double(lit.size() - 1)))]; };
    return {at(kPeakColourPercentile), at(1.0 - kPeakColourPercentile)};
}

}  // namespace

std::vector<float> peak_time_image(const io::Cube& cube, int isochrone_spacing,
                                   std::optional<float> level, float exposure) {
    const std::vector<int> peaks = peak_bins(cube);
    const std::vector<uint8_t> emitter = emitter_pixels(cube);
    const auto [kmin, kmax] = peak_colour_range(peaks, emitter);
    // The sparse volume of the thesis: only the radiance within two bins of each pixel's peak
    // (and, with isochrones, only every isochrone_spacing-th bin of it).
    std::vector<float> energy(peaks.size(), 0.f);
    for (int y = 0; y < cube.height; ++y)
        for (int x = 0; x < cube.width; ++x) {
            const size_t p = size_t(y) * size_t(cube.width) + size_t(x);
            const int k = peaks[p];
            if (k < 0) continue;
            double e = 0;
            for (int t = std::max(0, k - 2); t <= std::min(cube.bins - 1, k + 2); ++t)
                if (isochrone_spacing <= 0 || t % isochrone_spacing == 0)
                    e += lum(px(cube, x, y, t));
            energy[p] = float(e);
        }
    // The level as for any picture (reference_level), over the peak energies.
    const float ref =
        (level && *level > 0 ? *level : level_of(energy, emitter_pixels(cube), kLevelPercentile)) /
        std::exp2(exposure);
    const float norm = 1.f / std::log1p(kLogRange);
    std::vector<float> out(peaks.size() * 3, 0.f);
    for (size_t p = 0; p < peaks.size(); ++p) {
        if (peaks[p] < 0 || energy[p] <= 0) continue;
        const double u =
            kmax > kmin ? std::clamp(double(peaks[p] - kmin) / double(kmax - kmin), 0.0, 1.0) : 0.0;
        const Color c = time_colour(u);
        const float b = std::min(1.f, std::log1p(kLogRange * energy[p] / ref) * norm);
        out[3 * p + 0] = c.r * b;
        out[3 * p + 1] = c.g * b;
        out[3 * p + 2] = c.b * b;
    }
    return out;
}

std::vector<float> rainbow_fusion(const io::Cube& cube) {
    std::vector<Color> tint(size_t(cube.bins));
    for (int t = 0; t < cube.bins; ++t)
        tint[size_t(t)] = time_colour(cube.bins > 1 ? double(t) / double(cube.bins - 1) : 0.0);
    std::vector<float> out(size_t(cube.width) * size_t(cube.height) * 3, 0.f);
    for (int y = 0; y < cube.height; ++y)
        for (int x = 0; x < cube.width; ++x) {
            double s[3] = {0, 0, 0};
            for (int t = 0; t < cube.bins; ++t) {
                const float l = lum(px(cube, x, y, t));
                if (l == 0) continue;
                const Color& c = tint[size_t(t)];
                s[0] += double(l) * c.r;
                s[1] += double(l) * c.g;
                s[2] += double(l) * c.b;
            }
            float* o = &out[(size_t(y) * size_t(cube.width) + size_t(x)) * 3];
            for (int c = 0; c < 3; ++c) o[c] = float(s[c]);
        }
    return out;
}

std::vector<float> streak_slice(const io::Cube& cube, int y) {
    if (y < 0 || y >= cube.height)
        throw SceneError(
            fmt::format("row {} is out of range: the cube has rows 0 to {}", y, cube.height - 1));
    std::vector<float> out(size_t(cube.width) * size_t(cube.bins) * 3);
    for (int t = 0; t < cube.bins; ++t)
        for (int x = 0; x < cube.width; ++x) {
            const float* v = px(cube, x, y, t);
            float* o = &out[(size_t(t) * size_t(cube.width) + size_t(x)) * 3];
            o[0] = v[0];
            o[1] = v[1];
            o[2] = v[2];
        }
    return out;
}

namespace {

// Refuses cubes that cannot be unwarped to `target`, saying why.
void check_unwarpable(const io::Cube& cube, const TimeGrid& grid, TimeFrame target) {
    if (cube.depth.empty())
        throw SceneError(
            is_streak(cube)
                ? "the streak image has no channel Z (per-pixel sensor distance), which "
                  "unwarping needs: use the OUTBASE_rowRRRR.exr a streak film wrote, or a slice "
                  "of an OpenEXR cube (femto viz streak CUBE.exr --exr)"
                : "the cube has no depth part (per-pixel sensor distance), which unwarping "
                  "needs: use the OpenEXR cube a transient film wrote, not a .npy");
    if (!grid.known) throw SceneError("the cube has no time axis (femto:start, femto:bin_width)");
    if (grid.frame == target)
        throw SceneError(
            fmt::format("the cube is already in {} time (femto:time)", time_frame_name(target)));
    if (grid.frame == TimeFrame::Unknown)
        throw SceneError(
            "the cube does not say whether it holds camera or world time (femto:time)");
}

constexpr double kSnap = 1e-6;  // whole-bin shifts up to rounding stay exact
double snapped_floor(double v) {
    const double r = std::round(v);
    return std::abs(v - r) < kSnap ? r : std::floor(v);
}
double snapped_ceil(double v) {
    const double r = std::round(v);
    return std::abs(v - r) < kSnap ? r : std::ceil(v);
}

// Each pixel's shift in bins (new time = old time + shift * bin width) and the range of the
// shifts of the pixels that have a depth.
struct PixelShifts {
    std::vector<double> shift;
    double min = 0, max = 0;
    bool any = false;
};
PixelShifts pixel_shifts(const io::Cube& cube, double bin_width, bool to_world) {
    PixelShifts s;
    s.shift.assign(size_t(cube.width) * size_t(cube.height), 0.0);
    for (size_t p = 0; p < s.shift.size(); ++p) {
        const float d = cube.depth[p];
        if (!(d > 0) || !std::isfinite(d)) continue;
        s.shift[p] = (to_world ? -double(d) : double(d)) / bin_width;
        s.min = s.any ? std::min(s.min, s.shift[p]) : s.shift[p];
        s.max = s.any ? std::max(s.max, s.shift[p]) : s.shift[p];
        s.any = true;
    }
    return s;
}

// Resamples every pixel's time profile into out.data (out.bins bins, starting k_lo bins after
// the old start) by linear interpolation; returns the share of the energy that fell outside.
double resample_profiles(const io::Cube& cube, const std::vector<double>& shift, int64_t k_lo,
                         io::Cube& out) {
    const size_t pixels = shift.size(), T = size_t(cube.bins);
    const int64_t new_bins = out.bins;
    out.data.assign(pixels * size_t(new_bins) * 3, 0.f);
    double total = 0, kept = 0;
    for (size_t p = 0; p < pixels; ++p) {
        const float* in = &cube.data[p * T * 3];
        float* o = &out.data[p * size_t(new_bins) * 3];
        // New bin j covers old-bin coordinates [j + k_lo - shift, j + k_lo - shift + 1).
        double off = double(k_lo) - shift[p];
        double base = std::floor(off);
        if (std::abs(off - std::round(off)) < kSnap) base = off = std::round(off);
        const float f = float(off - base);
        const int64_t i0 = int64_t(base);
        for (int64_t j = 0; j < new_bins; ++j) {
            const int64_t a = j + i0, b = a + 1;
            for (int c = 0; c < 3; ++c) {
                float v = 0;
                if (a >= 0 && a < int64_t(T)) v += (1.f - f) * in[size_t(a) * 3 + size_t(c)];
                if (f > 0 && b >= 0 && b < int64_t(T)) v += f * in[size_t(b) * 3 + size_t(c)];
                o[size_t(j) * 3 + size_t(c)] = v;
            }
        }
        for (size_t i = 0; i < T * 3; ++i) total += in[i];
        for (size_t i = 0; i < size_t(new_bins) * 3; ++i) kept += o[i];
    }
    return total > 0 ? std::max(0.0, 1.0 - kept / total) : 0.0;
}

// Trims the cube's bins to those that hold energy (keeping the grid alignment); returns how
// many bins were cut from the front.
int64_t crop_to_energy(io::Cube& out) {
    const size_t pixels = size_t(out.width) * size_t(out.height);
    const int64_t n = out.bins;
    int64_t first = n, last = -1;
    for (size_t p = 0; p < pixels; ++p)
        for (int64_t j = 0; j < n; ++j) {
            const float* v = &out.data[(p * size_t(n) + size_t(j)) * 3];
            if (v[0] != 0 || v[1] != 0 || v[2] != 0) {
                first = std::min(first, j);
                last = std::max(last, j);
            }
        }
    if (!(last >= first && (first > 0 || last < n - 1))) return 0;
    const int64_t bins = last - first + 1;
    std::vector<float> cropped(pixels * size_t(bins) * 3);
    for (size_t p = 0; p < pixels; ++p)
        std::copy_n(&out.data[(p * size_t(n) + size_t(first)) * 3], size_t(bins) * 3,
                    &cropped[p * size_t(bins) * 3]);
    out.data = std::move(cropped);
    out.bins = int(bins);
    return first;
}

// The unwarped cube's time attributes: its frame, window (k_lo bins after the old start) and
// where it came from.
void set_unwarped_attributes(io::Cube& out, const io::Cube& cube, const TimeGrid& grid,
                             int64_t k_lo, bool to_world) {
    const double bw = grid.bin_width;
    set_attribute(out.attributes, "femto:time",
                  time_frame_name(to_world ? TimeFrame::World : TimeFrame::Camera));
    set_attribute(out.attributes, "femto:start", fmt::format("{}", grid.start + double(k_lo) * bw));
    set_attribute(out.attributes, "femto:bin_width", fmt::format("{}", bw));
    set_attribute(out.attributes, "femto:bins", std::to_string(out.bins));
    double start_ps = 0, bw_ps = 0;
    const std::string* sps = cube.attribute("femto:start_ps");
    const std::string* wps = cube.attribute("femto:bin_width_ps");
    if (sps && wps && parse_double(*sps, start_ps) && parse_double(*wps, bw_ps))
        set_attribute(out.attributes, "femto:start_ps",
                      fmt::format("{}", start_ps + double(k_lo) * bw_ps));
    set_attribute(out.attributes, "femto:unwarped",
                  to_world ? "camera -> world (eq. 4.1)" : "world -> camera (eq. 4.1)");
}

}  // namespace

UnwarpResult unwarp(const io::Cube& cube, const TimeGrid& grid, bool to_world, bool keep_window) {
    check_unwarpable(cube, grid, to_world ? TimeFrame::World : TimeFrame::Camera);
    const size_t pixels = size_t(cube.width) * size_t(cube.height);
    const PixelShifts shifts = pixel_shifts(cube, grid.bin_width, to_world);
    // Bin indices are 64-bit: a shift past 2^40 bins (a tiny --bin-width) would overflow them,
    // and would move every pixel's light far outside any window the cube could have.
    if (const double largest = std::max(std::abs(shifts.min), std::abs(shifts.max));
        largest > double(int64_t(1) << 40))
        throw SceneError(
            fmt::format("the depths shift pixels by up to {:.3g} bins of width {}: "
                        "too many (is the bin width right?)",
                        largest, grid.bin_width));
    int64_t k_lo = 0, k_hi = 0;  // the window grows by these many bins (unless kept)
    if (!keep_window && shifts.any) {
        k_lo = std::min<int64_t>(0, int64_t(snapped_floor(shifts.min)));
        k_hi = std::max<int64_t>(0, int64_t(snapped_ceil(shifts.max)));
    }
    const int64_t new_bins = int64_t(cube.bins) + k_hi - k_lo;
    const double bytes = double(pixels) * double(new_bins) * 3 * sizeof(float);
    if (new_bins > (int64_t(1) << 20) || bytes > double(int64_t(1) << 36))
        throw SceneError(fmt::format("the unwarped cube would need {} bins: too large", new_bins));
    // Allocated beside the cube read: more than the machine holds would end in an allocation
    // failure or the kernel's OOM killer, not a message.
    if (const std::string problem =
            memory_shortfall(bytes, fmt::format("the unwarped cube ({} bins)", new_bins));
        !problem.empty())
        throw SceneError(problem);
    UnwarpResult result;
    io::Cube& out = result.cube;
    out.width = cube.width;
    out.height = cube.height;
    out.bins = int(new_bins);
    out.depth = cube.depth;
    // Part names and types are the writer's business (read_exr_cube returns part 0's).
    for (const auto& [k, v] : cube.attributes)
        if (k != "name" && k != "type") out.attributes.emplace_back(k, v);
    result.dropped = resample_profiles(cube, shifts.shift, k_lo, out);
    if (!keep_window) k_lo += crop_to_energy(out);
    set_unwarped_attributes(out, cube, grid, k_lo, to_world);
    return result;
}

void write_png8(const std::string& path, int width, int height, const std::vector<float>& display) {
    io::detail::write_png_display(path, width, height, display);
}

void write_gif(const std::string& path, int width, int height,
               const std::vector<std::vector<float>>& frames, int fps) {
    if (frames.empty()) throw SceneError(fmt::format("cannot write \"{}\": no frames", path));
    const io::detail::OiioModule& oiio = io::detail::oiio_module();
    std::vector<std::vector<unsigned char>> bytes;
    for (const std::vector<float>& frame : frames)
        bytes.push_back(io::detail::display_bytes(frame));
    const std::string tmp = temp_path_for(path);
    if (const std::string err = oiio.write_gif(tmp, width, height, bytes, std::max(1, fps));
        !err.empty())
        fail_write(tmp, path, err);
    commit(tmp, path);
}

void write_streak_exr(const std::string& path, const io::Cube& cube, int y,
                      io::Attributes attributes) {
    const std::vector<float> rgb = streak_slice(cube, y);  // checks y
    std::vector<float> depth;
    if (!cube.depth.empty()) {
        const float* row = &cube.depth[size_t(y) * size_t(cube.width)];
        depth.resize(size_t(cube.width) * size_t(cube.bins));
        for (size_t t = 0; t < size_t(cube.bins); ++t)
            std::copy_n(row, size_t(cube.width), &depth[t * size_t(cube.width)]);
    }
    set_attribute(attributes, "femto:layout", kStreakLayout);
    io::write_exr_rgb(path, cube.width, cube.bins, rgb.data(), attributes,
                      depth.empty() ? nullptr : depth.data());
}

void write_exr_gray(const std::string& path, int width, int height, const float* values,
                    const io::Attributes& attributes) {
    io::detail::write_exr_channels(path, width, height, {{"Y", values, 1}}, attributes);
}

}  // namespace femto::viz
