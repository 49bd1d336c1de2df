// gridvolume: values on a voxel grid read from a Mitsuba `gridvolume` binary file (.vol), as
// Mitsuba 0.6's and Mitsuba 3's `gridvolume`: a density for a heterogeneous medium (1 channel)
// or an albedo (1 or 3 channels).
//
// The .vol file (Mitsuba 0.6 documentation, `gridvolume`), little-endian:
//     bytes 'V' 'O' 'L', version byte 3; int32 encoding (1 = float32, the only one read here);
//     int32 xres, yres, zres; int32 channels; 6 float32, the bounding box (xmin, ymin, zmin,
//     xmax, ymax, zmax); then xres * yres * zres * channels float32 values, value (x, y, z, c)
//     at index ((z * yres + y) * xres + x) * channels + c.
//
// Where the data lies, in the volume's own coordinates, which `to_world` places in the scene:
// - the box: the unit cube (Mitsuba 3's default), the file's box with `use_grid_bbox` (Mitsuba
//   3; 0.x files imply it, as Mitsuba 0.6 always used it), or `min` / `max` (Mitsuba 0.6);
// - the lattice: `cell` (Mitsuba 3): the box is cut into res cells per axis and value i sits at
//   the centre of cell i; between the outer centres and the faces `wrap_mode` decides (clamp:
//   the edge value). `vertex` (Mitsuba 0.6; 0.x files imply it): value i sits at min + i /
//   (res - 1) * (max - min), so the first and last lie on the faces (an axis with res 1 is
//   constant along it).
// Values are interpolated trilinearly (or `filter_type` nearest) inside the box; outside it
// the volume is 0, which is where Mitsuba's heterogeneous media end too.
//
// Bad input (missing or truncated file, wrong magic, version or encoding, absurd or
// inconsistent sizes, a channel count other than 1 or 3, NaN, infinite or negative values) is
// a SceneError at the `filename` parameter that names the file.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "femto/input_file.h"
#include "femto/plugin.h"
#include "femto/transform.h"
#include "femto/volume.h"

namespace {

using femto::Color;
using femto::Properties;
using femto::Vec3;

constexpr size_t kHeaderBytes = 48;
/// Largest number of values accepted (8 GiB of float32).
constexpr uint64_t kMaxValues = uint64_t(1) << 31;

template <typename T>
std::string to_str(const T& v) {
    std::ostringstream os;
    os << v;
    return os.str();
}

uint32_t load_u32(const unsigned char* b) {
    uint32_t v;
    std::memcpy(&v, b, 4);
    if constexpr (std::endian::native == std::endian::big) v = __builtin_bswap32(v);
    return v;
}
int32_t load_i32(const unsigned char* b) { return static_cast<int32_t>(load_u32(b)); }
float load_f32(const unsigned char* b) { return std::bit_cast<float>(load_u32(b)); }

using Vec3d = std::array<double, 3>;

/// p' = M p for the affine part of a row-major 4x4 matrix, in double precision.
Vec3d apply_point(const femto::Transform::Matrix& m, const Vec3d& p) {
    Vec3d r{};
    for (int i = 0; i < 3; ++i) r[i] = m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3];
    return r;
}
Vec3d apply_vector(const femto::Transform::Matrix& m, const Vec3d& v) {
    Vec3d r{};
    for (int i = 0; i < 3; ++i) r[i] = m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2];
    return r;
}
Vec3d to_d(const Vec3& v) { return {double(v.x), double(v.y), double(v.z)}; }

enum class Lattice { Cell, Vertex };
enum class Wrap { Clamp, Repeat, Mirror };

/// One of `names` (the values a string parameter takes), as its index.
int choose(const Properties& props, const char* name, const char* def,
           std::initializer_list<const char*> names) {
    const std::string v = props.get_string(name, def);
    int i = 0;
    std::string valid;
    for (const char* n : names) {
        if (v == n) return i;
        valid += std::string(i++ ? ", " : "") + n;
    }
    props.fail(name, "unknown " + std::string(name) + " \"" + v + "\"; valid: " + valid);
}

class GridVolume final : public femto::Volume {
public:
    explicit GridVolume(const Properties& props) {
        const std::string filename = props.get_string("filename");
        lattice_ = Lattice(choose(props, "lattice", "cell", {"cell", "vertex"}));
        nearest_ = choose(props, "filter_type", "trilinear", {"trilinear", "nearest"}) == 1;
        wrap_ = Wrap(choose(props, "wrap_mode", "clamp", {"clamp", "repeat", "mirror"}));
        const bool use_grid_bbox = props.get_bool("use_grid_bbox", false);
        // Mitsuba's switches that change nothing here: 0.6 network rendering, Mitsuba 3's
        // spectral upsampling (femto renders RGB) and GPU texture units.
        props.get_bool("send_data", false);
        props.get_bool("raw", false);
        props.get_bool("accel", true);

        const femto::Transform to_world = props.get_transform("to_world", femto::Transform());
        const auto& m = to_world.matrix();
        if (m[3][0] != 0 || m[3][1] != 0 || m[3][2] != 0 || m[3][3] != 1)
            props.fail("to_world", "to_world must be affine (no projective part)");
        to_local_ = to_world.inverse_matrix();

        load(props, filename);
        choose_box(props, filename, use_grid_bbox);
        longest_chord_ = chord(to_world);
    }

    int channels() const override { return channels_; }

    Color eval(const Vec3& p) const override {
        float v[3] = {0.f, 0.f, 0.f};
        lookup(apply_point(to_local_, to_d(p)), v);
        return channels_ == 1 ? Color(v[0]) : Color(v[0], v[1], v[2]);
    }

    double eval_1(const Vec3& p) const override {
        float v[3] = {0.f, 0.f, 0.f};
        return lookup(apply_point(to_local_, to_d(p)), v);
    }

    Color min_value() const override { return min_; }
    Color max_value() const override { return max_; }

    bool clip(const femto::Ray& ray, double& t0, double& t1) const override {
        // In the grid's coordinates the ray parameter is the same (to_world is affine).
        const Vec3d o = apply_point(to_local_, to_d(ray.o));
        const Vec3d d = apply_vector(to_local_, to_d(ray.d));
        for (int a = 0; a < 3; ++a) {
            if (d[a] == 0.0) {
                if (!(o[a] >= lo_[a] && o[a] <= hi_[a])) return false;
                continue;
            }
            const double inv = 1.0 / d[a];
            double ta = (lo_[a] - o[a]) * inv, tb = (hi_[a] - o[a]) * inv;
            if (ta > tb) std::swap(ta, tb);
            t0 = std::max(t0, ta);
            t1 = std::min(t1, tb);
        }
        return t0 < t1;  // false also for NaN input
    }

    double longest_chord() const override { return longest_chord_; }

private:
    [[noreturn]] static void fail_file(const Properties& props, const std::string& filename,
                                       const std::string& what) {
        props.fail("filename", "grid volume \"" + filename + "\": " + what);
    }

    void load(const Properties& props, const std::string& filename) {
        auto fail = [&](const std::string& what) { fail_file(props, filename, what); };
        if (filename.empty()) fail("empty file name");
        femto::InputFile in(filename, props.location_of("filename"));
        unsigned char h[kHeaderBytes];
        const size_t got = in.read(h, kHeaderBytes);
        read_header(h, got, in.size(), fail);
        const uint64_t count = values_;
        data_.resize(count);
        if (in.read(data_.data(), count * sizeof(float)) != count * sizeof(float))
            fail("could not read the " + std::to_string(count) + " values (the file shrank)");
        if constexpr (std::endian::native == std::endian::big)
            for (float& v : data_)
                v = std::bit_cast<float>(__builtin_bswap32(std::bit_cast<uint32_t>(v)));
        check_values(fail);
    }

    template <typename Fail>
    void read_header(const unsigned char* h, size_t got, uint64_t file_size, const Fail& fail) {
        if (got < 4 || h[0] != 'V' || h[1] != 'O' || h[2] != 'L')
            fail(
                "not a Mitsuba grid volume (.vol) file (it does not start with the bytes "
                "'V' 'O' 'L')");
        if (h[3] != 3)
            fail("file format version " + std::to_string(int(h[3])) +
                 " is not supported (only version 3)");
        if (got < kHeaderBytes)
            fail("truncated header: the file has " + std::to_string(file_size) +
                 " bytes, a .vol header has " + std::to_string(kHeaderBytes));
        const int32_t encoding = load_i32(h + 4);
        if (encoding != 1) {
            const char* names[] = {"", "float32", "float16", "uint8", "quantized directions"};
            const std::string name =
                encoding >= 1 && encoding <= 4 ? std::string(" (") + names[encoding] + ")" : "";
            fail("encoding " + std::to_string(encoding) + name +
                 " is not supported; femto reads encoding 1 (float32)");
        }
        for (int a = 0; a < 3; ++a) {
            res_[a] = load_i32(h + 8 + 4 * a);
            if (res_[a] < 1)
                fail("invalid resolution " + std::to_string(load_i32(h + 8)) + " x " +
                     std::to_string(load_i32(h + 12)) + " x " + std::to_string(load_i32(h + 16)) +
                     " (every axis needs at least 1 point)");
        }
        channels_ = load_i32(h + 20);
        if (channels_ != 1 && channels_ != 3)
            fail("has " + std::to_string(channels_) +
                 " channels per voxel; femto reads 1 (a density) or 3 (a colour)");
        const std::string dims = std::to_string(res_[0]) + " x " + std::to_string(res_[1]) + " x " +
                                 std::to_string(res_[2]);
        values_ = uint64_t(channels_);
        for (int a = 0; a < 3; ++a) {
            if (uint64_t(res_[a]) > kMaxValues / values_)
                fail("resolution " + dims + " has more than 2^31 values");
            values_ *= uint64_t(res_[a]);
        }
        const uint64_t expected = kHeaderBytes + values_ * sizeof(float);
        if (file_size != expected)
            fail("has " + std::to_string(file_size) + " bytes but a float32 grid of " + dims +
                 " x " + std::to_string(channels_) + " channel(s) needs " +
                 std::to_string(expected) +
                 (file_size < expected ? " (the file is truncated)" : " (trailing data)"));
        for (int a = 0; a < 3; ++a) {
            file_lo_[a] = load_f32(h + 24 + 4 * a);
            file_hi_[a] = load_f32(h + 36 + 4 * a);
        }
    }

    template <typename Fail>
    void check_values(const Fail& fail) {
        float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {0.f, 0.f, 0.f};
        for (uint64_t i = 0; i < values_; ++i) {
            const float v = data_[i];
            const int c = int(i % uint64_t(channels_));
            if (!std::isfinite(v) || v < 0.f) {
                const uint64_t voxel = i / uint64_t(channels_);
                const uint64_t x = voxel % uint64_t(res_[0]);
                const uint64_t y = (voxel / uint64_t(res_[0])) % uint64_t(res_[1]);
                const uint64_t z = voxel / (uint64_t(res_[0]) * uint64_t(res_[1]));
                fail("value " + to_str(v) + " at voxel (x " + std::to_string(x) + ", y " +
                     std::to_string(y) + ", z " + std::to_string(z) +
                     (channels_ > 1 ? ", channel " + std::to_string(c) : std::string()) +
                     "); values must be finite and >= 0");
            }
            lo[c] = std::min(lo[c], v);
            hi[c] = std::max(hi[c], v);
        }
        min_ = channels_ == 1 ? Color(lo[0]) : Color(lo[0], lo[1], lo[2]);
        max_ = channels_ == 1 ? Color(hi[0]) : Color(hi[0], hi[1], hi[2]);
    }

    void choose_box(const Properties& props, const std::string& filename, bool use_grid_bbox) {
        const bool given = props.has("min") || props.has("max");
        if (given) {
            const Vec3 lo = props.get_point("min"), hi = props.get_point("max");
            for (int a = 0; a < 3; ++a) {
                lo_[a] = lo[a];
                hi_[a] = hi[a];
            }
        } else {
            for (int a = 0; a < 3; ++a) {
                lo_[a] = use_grid_bbox ? file_lo_[a] : 0.0;
                hi_[a] = use_grid_bbox ? file_hi_[a] : 1.0;
            }
        }
        for (int a = 0; a < 3; ++a)
            if (!std::isfinite(lo_[a]) || !std::isfinite(hi_[a]) || !(lo_[a] < hi_[a]))
                props.fail(given ? "min" : "filename",
                           "grid volume \"" + filename + "\": invalid bounding box (" +
                               to_str(lo_[0]) + ", " + to_str(lo_[1]) + ", " + to_str(lo_[2]) +
                               ") - (" + to_str(hi_[0]) + ", " + to_str(hi_[1]) + ", " +
                               to_str(hi_[2]) + "): it needs finite min < max on every axis");
        for (int a = 0; a < 3; ++a) {
            const double cells = lattice_ == Lattice::Cell ? res_[a] : std::max(res_[a] - 1, 0);
            to_grid_[a] = cells / (hi_[a] - lo_[a]);
        }
        stride_[0] = channels_;
        stride_[1] = int64_t(res_[0]) * channels_;
        stride_[2] = int64_t(res_[0]) * res_[1] * channels_;
    }

    // Longest chord through the box in the scene: its longest diagonal after to_world.
    double chord(const femto::Transform& to_world) const {
        double longest = 0.0;
        for (int corner = 0; corner < 4; ++corner) {
            const Vec3d diagonal{(corner & 1 ? -1 : 1) * (hi_[0] - lo_[0]),
                                 (corner & 2 ? -1 : 1) * (hi_[1] - lo_[1]), hi_[2] - lo_[2]};
            const Vec3d d = apply_vector(to_world.matrix(), diagonal);
            longest = std::max(longest, std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
        }
        return longest;
    }

    /// Index `i` of axis `a` brought into the grid by the wrap mode.
    int64_t wrap(int64_t i, int a) const {
        const int64_t n = res_[a];
        if (i >= 0 && i < n) return i;
        if (wrap_ == Wrap::Repeat) return ((i % n) + n) % n;
        if (wrap_ == Wrap::Mirror) {
            const int64_t m = ((i % (2 * n)) + 2 * n) % (2 * n);
            return m < n ? m : 2 * n - 1 - m;
        }
        return std::clamp<int64_t>(i, 0, n - 1);
    }

    /// The value at `q` (grid coordinates) into `out` (channels_ values); returns channel 0.
    /// Zero outside the box (or at a NaN point).
    double lookup(const Vec3d& q, float* out) const {
        double g[3];
        for (int a = 0; a < 3; ++a) {
            if (!(q[a] >= lo_[a] && q[a] <= hi_[a])) return 0.0;
            g[a] = (q[a] - lo_[a]) * to_grid_[a] - (lattice_ == Lattice::Cell ? 0.5 : 0.0);
        }
        if (nearest_) {
            int64_t offset = 0;
            for (int a = 0; a < 3; ++a) {
                const double x =
                    lattice_ == Lattice::Cell ? std::floor(g[a] + 0.5) : std::round(g[a]);
                offset += wrap(int64_t(x), a) * stride_[a];
            }
            for (int c = 0; c < channels_; ++c) out[c] = data_[size_t(offset) + c];
            return out[0];
        }
        int64_t idx[3][2];
        double f[3];
        for (int a = 0; a < 3; ++a) {
            const double i0 = std::floor(g[a]);
            f[a] = std::clamp(g[a] - i0, 0.0, 1.0);
            idx[a][0] = wrap(int64_t(i0), a) * stride_[a];
            idx[a][1] = wrap(int64_t(i0) + 1, a) * stride_[a];
        }
        for (int c = 0; c < channels_; ++c) {
            auto at = [&](int dx, int dy, int dz) {
                return double(data_[size_t(idx[0][dx] + idx[1][dy] + idx[2][dz]) + c]);
            };
            const double c00 = at(0, 0, 0) * (1 - f[0]) + at(1, 0, 0) * f[0];
            const double c10 = at(0, 1, 0) * (1 - f[0]) + at(1, 1, 0) * f[0];
            const double c01 = at(0, 0, 1) * (1 - f[0]) + at(1, 0, 1) * f[0];
            const double c11 = at(0, 1, 1) * (1 - f[0]) + at(1, 1, 1) * f[0];
            const double c0 = c00 * (1 - f[1]) + c10 * f[1];
            const double c1 = c01 * (1 - f[1]) + c11 * f[1];
            const double v = c0 * (1 - f[2]) + c1 * f[2];
            if (c == 0) {
                out[0] = float(v);
                if (channels_ == 1) return v;
                continue;
            }
            out[c] = float(v);
        }
        return double(out[0]);
    }

    Lattice lattice_ = Lattice::Cell;
    Wrap wrap_ = Wrap::Clamp;
    bool nearest_ = false;
    femto::Transform::Matrix to_local_{};
    int32_t res_[3] = {0, 0, 0};
    int channels_ = 1;
    uint64_t values_ = 0;
    int64_t stride_[3] = {0, 0, 0};
    double file_lo_[3] = {0, 0, 0}, file_hi_[3] = {0, 0, 0};
    double lo_[3] = {0, 0, 0}, hi_[3] = {0, 0, 0}, to_grid_[3] = {0, 0, 0};
    double longest_chord_ = 0;
    std::vector<float> data_;
    Color min_, max_;
};

}  // namespace

FEMTO_PLUGIN(GridVolume, femto::PluginKind::Volume, "gridvolume",
             "Values on a voxel grid from a Mitsuba .vol file (float32, 1 or 3 channels), "
             "interpolated trilinearly; 0 outside its box",
             {{"filename", "filename", "", "the .vol file"},
              {"to_world", "transform", "identity", "places the grid's box in the scene"},
              {"use_grid_bbox", "boolean", "false",
               "the box is the one stored in the file (true; 0.x files imply it) or the unit "
               "cube (false, Mitsuba 3's default)"},
              {"lattice", "string", "cell",
               "cell: value i at the centre of cell i of res cells per axis (Mitsuba 3); "
               "vertex: value i at min + i / (res - 1) * (max - min), the first and last on the "
               "faces (Mitsuba 0.6; 0.x files imply it)"},
              {"filter_type", "string", "trilinear", "trilinear or nearest"},
              {"wrap_mode", "string", "clamp",
               "clamp, repeat or mirror: the values between the outer cell centres and the "
               "box's faces (cell lattice)"},
              {"min", "point", "", "Mitsuba 0.6: the box's lower corner, replacing the file's"},
              {"max", "point", "", "Mitsuba 0.6: the box's upper corner, with min"},
              {"send_data", "boolean", "false", "Mitsuba 0.6 (network rendering); ignored"},
              {"raw", "boolean", "false", "Mitsuba 3 (no spectral upsampling); femto is RGB"},
              {"accel", "boolean", "true", "Mitsuba 3 (GPU texture units); ignored"}})
