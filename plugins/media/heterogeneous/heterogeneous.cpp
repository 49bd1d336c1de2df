// heterogeneous: a participating medium whose density comes from a voxel grid in Mitsuba's
// `gridvolume` binary format (.vol), as Mitsuba 0.6's `heterogeneous` medium.
//
//     sigma_t(p) = scale * density(p),   sigma_s(p) = albedo * sigma_t(p)
//
// The .vol file (Mitsuba 0.6 documentation, `gridvolume`), little-endian:
//     bytes 'V' 'O' 'L', version byte 3; int32 encoding (1 = float32, the only one read here);
//     int32 xres, yres, zres; int32 channels (1: a density grid); 6 float32, the bounding box
//     (xmin, ymin, zmin, xmax, ymax, zmax); then xres * yres * zres * channels float32 values,
//     value (x, y, z, c) at index ((z * yres + y) * xres + x) * channels + c.
//
// Lookups follow Mitsuba 0.6's gridvolume: the data points sit on a lattice spanning the
// bounding box, point (x, y, z) at min + (x / (xres - 1), y / (yres - 1), z / (zres - 1)) *
// (max - min), so the first and last points lie on the box's faces; density(p) is the
// trilinear interpolation of the eight surrounding points inside the box and 0 outside it. An
// axis with a single data point (resolution 1, where Mitsuba 0.6 would return 0 everywhere) is
// constant along that axis. `to_world` places the box (given in the file's coordinates) in the
// scene; densities are per scene unit of length, as in Mitsuba.
//
// `albedo` defaults to 0.75, Mitsuba 3's default (Mitsuba 0.6 has no default: its albedo is a
// required volume). `eta` and the nested <phase> are read by the Medium base class.
//
// transmittance() is an unbiased estimate by residual ratio tracking (Novak et al. 2014) with a
// constant control: the ray is clipped to the box (transmittance is exactly 1 outside), the
// control extinction mu_c = scale * min(density) is integrated exactly, exp(-mu_c L), and the
// residual sigma_t - mu_c is ratio-tracked with its majorant scale * (max - min) density. For
// grids whose minimum is 0 (most) this is plain ratio tracking with majorant(); a constant grid
// gives the exact exp(-sigma_t L) with no random numbers drawn. Estimates that fall below 0.1
// are Russian-rouletted (kept with probability T / 0.1, then worth 0.1), which is unbiased and
// bounds the work through thick media.
//
// Bad input (missing or truncated file, wrong magic, version or encoding, absurd or
// inconsistent sizes, NaN, infinite or negative densities) is a SceneError naming the file.
// So is a grid whose tracking would take more than 1e4 steps along a ray through it: scale *
// (largest - smallest density) times the longest chord through its box in the scene.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "femto/input_file.h"
#include "femto/medium.h"
#include "femto/plugin.h"
#include "femto/sampler.h"
#include "femto/transform.h"

namespace {

namespace fs = std::filesystem;
using femto::Color;
using femto::Properties;
using femto::Vec3;

constexpr size_t kHeaderBytes = 48;
/// Largest number of voxels accepted (8 GiB of float32).
constexpr uint64_t kMaxVoxels = uint64_t(1) << 31;
/// Largest expected number of ratio-tracking steps along a ray through the grid (residual
/// majorant x longest chord through the box).
constexpr double kMaxTrackingSteps = 1e4;
/// Ratio-tracking estimates below this are Russian-rouletted.
constexpr double kRouletteThreshold = 0.1;

std::string quoted(const std::string& s) { return "\"" + s + "\""; }

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

/// p' = M p for the affine part of a row-major 4x4 matrix, in double precision.
std::array<double, 3> apply_point(const femto::Transform::Matrix& m, const Vec3& p) {
    std::array<double, 3> r{};
    for (int i = 0; i < 3; ++i) r[i] = m[i][0] * p.x + m[i][1] * p.y + m[i][2] * p.z + m[i][3];
    return r;
}
std::array<double, 3> apply_vector(const femto::Transform::Matrix& m, const Vec3& v) {
    std::array<double, 3> r{};
    for (int i = 0; i < 3; ++i) r[i] = m[i][0] * v.x + m[i][1] * v.y + m[i][2] * v.z;
    return r;
}

class HeterogeneousMedium final : public femto::Medium {
public:
    explicit HeterogeneousMedium(const Properties& props) : femto::Medium(props) {
        if (props.has("density") && props.type("density") == Properties::Type::Object)
            props.fail("density",
                       "heterogeneous takes the density grid's file name directly, as "
                       "<string name=\"density\" value=\"smoke.vol\"/>; a nested <volume> is not "
                       "supported");
        const std::string filename = resolve(props, props.get_string("density"));

        albedo_ = props.get_color("albedo", Color(0.75f));
        for (int c = 0; c < 3; ++c)
            if (!(albedo_[c] >= 0.f && albedo_[c] <= 1.f))
                props.fail("albedo",
                           "albedo (the single-scattering albedo) must lie in [0, 1] "
                           "in every channel, not " +
                               to_str(albedo_[c]));
        scale_ = props.get_float("scale", 1.0);
        if (!(scale_ >= 0.0) || !std::isfinite(scale_))
            props.fail("scale", "scale must be finite and >= 0, not " + to_str(scale_));

        const femto::Transform to_world = props.get_transform("to_world", femto::Transform());
        const auto& m = to_world.matrix();
        if (m[3][0] != 0 || m[3][1] != 0 || m[3][2] != 0 || m[3][3] != 1)
            props.fail("to_world", "to_world must be affine (no projective part)");
        to_local_ = to_world.inverse_matrix();

        load(props, filename);

        min_sigma_ = scale_ * min_density_;
        max_sigma_ = scale_ * max_density_;
        residual_majorant_ = max_sigma_ - min_sigma_;
        check_tracking_work(props, to_world);
    }

    bool homogeneous() const override { return false; }

    float majorant() const override { return static_cast<float>(max_sigma_); }

    Color sigma_t(const Vec3& p) const override {
        return Color(static_cast<float>(scale_ * density(apply_point(to_local_, p), false)));
    }

    Color sigma_s(const Vec3& p) const override { return albedo_ * sigma_t(p)[0]; }

    Color transmittance(const femto::Ray& ray, double distance,
                        femto::Sampler& sampler) const override {
        // Clip [0, distance] to the box, in the grid's coordinates (the ray parameter is the
        // same in both spaces since to_world is affine).
        const std::array<double, 3> o = apply_point(to_local_, ray.o);
        const std::array<double, 3> d = apply_vector(to_local_, ray.d);
        double t0 = 0.0, t1 = distance;
        if (!(t1 > 0.0)) return Color(1.f);
        for (int a = 0; a < 3; ++a) {
            if (d[a] == 0.0) {
                if (!(o[a] >= bmin_[a] && o[a] <= bmax_[a])) return Color(1.f);
                continue;
            }
            const double inv = 1.0 / d[a];
            double ta = (bmin_[a] - o[a]) * inv, tb = (bmax_[a] - o[a]) * inv;
            if (ta > tb) std::swap(ta, tb);
            t0 = std::max(t0, ta);
            t1 = std::min(t1, tb);
        }
        if (!(t0 < t1)) return Color(1.f);  // misses the box (or NaN input)

        double tr = std::exp(-min_sigma_ * (t1 - t0));
        if (!(residual_majorant_ > 0.0) || tr == 0.0) return Color(static_cast<float>(tr));
        const double inv_majorant = 1.0 / residual_majorant_;
        double t = t0;
        for (;;) {
            const double u = sampler.next_1d();
            t -= std::log1p(-std::min(u, 1.0 - 1e-16)) * inv_majorant;
            if (!(t < t1)) break;
            const std::array<double, 3> p{o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t};
            // 1 - (sigma_t - mu_c) / (max - mu_c), written so that it is exactly 0 at the max.
            tr *= std::clamp((max_sigma_ - scale_ * density(p, true)) * inv_majorant, 0.0, 1.0);
            if (tr < kRouletteThreshold) {
                if (tr <= 0.0 || sampler.next_1d() >= tr / kRouletteThreshold) return Color(0.f);
                tr = kRouletteThreshold;
            }
        }
        return Color(static_cast<float>(tr));
    }

private:
    /// A relative name is looked up next to the scene file the parameter was written in (as
    /// Mitsuba resolves file names; the loader resolves only parameters named `filename`
    /// itself), then from the working directory; errors name the scene-relative path.
    static std::string resolve(const Properties& props, const std::string& name) {
        const fs::path p(name);
        std::error_code ec;
        if (name.empty() || p.is_absolute()) return name;
        const std::string& scene_file = props.location_of("density").file;
        if (!scene_file.empty()) {
            const fs::path candidate = (fs::path(scene_file).parent_path() / p).lexically_normal();
            if (fs::exists(candidate, ec) || !fs::exists(p, ec)) return candidate.string();
        }
        return name;
    }

    // Ratio tracking takes about residual majorant x chord steps along a ray through the box
    // (more where the grid is nearly empty: nothing ends the walk early). A voxel of density
    // 1e6 made renders of a second take minutes; such grids are refused.
    void check_tracking_work(const Properties& props, const femto::Transform& to_world) const {
        double chord = 0.0;  // longest chord through the box: its longest diagonal, in the scene
        for (int corner = 0; corner < 4; ++corner) {
            const Vec3 diagonal(float((corner & 1 ? -1 : 1) * (bmax_[0] - bmin_[0])),
                                float((corner & 2 ? -1 : 1) * (bmax_[1] - bmin_[1])),
                                float(bmax_[2] - bmin_[2]));
            const std::array<double, 3> d = apply_vector(to_world.matrix(), diagonal);
            chord = std::max(chord, std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
        }
        const double steps = residual_majorant_ * chord;
        if (!(steps <= kMaxTrackingSteps))
            props.fail("scale",
                       "the density grid's majorant (scale * (largest - smallest density) = " +
                           to_str(residual_majorant_) +
                           " per scene unit) times the longest chord "
                           "through its box (" +
                           to_str(chord) + " scene units) is " + to_str(steps) +
                           ": tracking a ray through it would take about that many density "
                           "lookups, and femto accepts at most " +
                           to_str(kMaxTrackingSteps) +
                           " (lower the scale, or the densities, of the grid)");
    }

    [[noreturn]] static void fail_file(const Properties& props, const std::string& filename,
                                       const std::string& what) {
        props.fail("density", "density grid " + quoted(filename) + ": " + what);
    }

    void load(const Properties& props, const std::string& filename) {
        auto fail = [&](const std::string& what) { fail_file(props, filename, what); };
        if (filename.empty()) fail("empty file name");
        femto::InputFile in(filename, props.location_of("density"));
        const uint64_t file_size = in.size();

        unsigned char h[kHeaderBytes];
        const size_t got = in.read(h, kHeaderBytes);
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
        const int32_t channels = load_i32(h + 20);
        if (channels != 1)
            fail("has " + std::to_string(channels) +
                 " channels per voxel; a density grid has exactly 1");
        const std::string dims = std::to_string(res_[0]) + " x " + std::to_string(res_[1]) + " x " +
                                 std::to_string(res_[2]);
        uint64_t voxels = 1;
        for (int a = 0; a < 3; ++a) {
            if (uint64_t(res_[a]) > kMaxVoxels / voxels)
                fail("resolution " + dims + " has more than 2^31 voxels");
            voxels *= uint64_t(res_[a]);
        }
        const uint64_t expected = kHeaderBytes + voxels * sizeof(float);
        if (file_size != expected)
            fail("has " + std::to_string(file_size) + " bytes but a float32 grid of " + dims +
                 " needs " + std::to_string(expected) +
                 (file_size < expected ? " (the file is truncated)" : " (trailing data)"));
        for (int a = 0; a < 3; ++a) {
            bmin_[a] = load_f32(h + 24 + 4 * a);
            bmax_[a] = load_f32(h + 36 + 4 * a);
        }
        for (int a = 0; a < 3; ++a)
            if (!std::isfinite(bmin_[a]) || !std::isfinite(bmax_[a]) || !(bmin_[a] < bmax_[a]))
                fail("invalid bounding box (" + to_str(bmin_[0]) + ", " + to_str(bmin_[1]) + ", " +
                     to_str(bmin_[2]) + ") - (" + to_str(bmax_[0]) + ", " + to_str(bmax_[1]) +
                     ", " + to_str(bmax_[2]) + "): it needs finite min < max on every axis");

        data_.resize(voxels);
        if (in.read(data_.data(), voxels * sizeof(float)) != voxels * sizeof(float))
            fail("could not read the " + std::to_string(voxels) + " densities (the file shrank)");
        if constexpr (std::endian::native == std::endian::big)
            for (float& v : data_)
                v = std::bit_cast<float>(__builtin_bswap32(std::bit_cast<uint32_t>(v)));

        min_density_ = std::numeric_limits<double>::infinity();
        max_density_ = 0.0;
        for (uint64_t i = 0; i < voxels; ++i) {
            const float v = data_[i];
            if (!std::isfinite(v) || v < 0.f) {
                const uint64_t x = i % uint64_t(res_[0]);
                const uint64_t y = (i / uint64_t(res_[0])) % uint64_t(res_[1]);
                const uint64_t z = i / (uint64_t(res_[0]) * uint64_t(res_[1]));
                fail("density " + to_str(v) + " at voxel (x " + std::to_string(x) + ", y " +
                     std::to_string(y) + ", z " + std::to_string(z) +
                     "); densities must be finite and >= 0");
            }
            min_density_ = std::min(min_density_, double(v));
            max_density_ = std::max(max_density_, double(v));
        }
        for (int a = 0; a < 3; ++a)
            to_grid_[a] = res_[a] > 1 ? (res_[a] - 1) / (bmax_[a] - bmin_[a]) : 0.0;
        stride_[0] = 1;
        stride_[1] = res_[0];
        stride_[2] = int64_t(res_[0]) * res_[1];
        // If the scale overflows a float (density * scale), the majorant would be infinite.
        if (!std::isfinite(static_cast<float>(scale_ * max_density_)))
            props.fail("scale", "scale * the largest density (" + to_str(scale_ * max_density_) +
                                    ") overflows");
    }

    /// Trilinear density at `p` (grid coordinates); 0 outside the box unless `clamp_to_box`.
    double density(const std::array<double, 3>& p, bool clamp_to_box) const {
        int64_t offset = 0;
        int64_t step[3];
        double f[3];
        for (int a = 0; a < 3; ++a) {
            double x = p[a];
            if (clamp_to_box) {
                x = std::clamp(x, bmin_[a], bmax_[a]);
            } else if (!(x >= bmin_[a] && x <= bmax_[a])) {
                return 0.0;  // outside, or NaN
            }
            if (res_[a] == 1) {
                f[a] = 0.0;
                step[a] = 0;
                continue;
            }
            const double g = (x - bmin_[a]) * to_grid_[a];
            const int64_t i =
                std::clamp<int64_t>(static_cast<int64_t>(std::floor(g)), 0, int64_t(res_[a]) - 2);
            f[a] = std::clamp(g - double(i), 0.0, 1.0);
            offset += i * stride_[a];
            step[a] = stride_[a];
        }
        const float* v = data_.data() + offset;
        auto at = [&](int dx, int dy, int dz) {
            return double(v[dx * step[0] + dy * step[1] + dz * step[2]]);
        };
        const double c00 = at(0, 0, 0) * (1 - f[0]) + at(1, 0, 0) * f[0];
        const double c10 = at(0, 1, 0) * (1 - f[0]) + at(1, 1, 0) * f[0];
        const double c01 = at(0, 0, 1) * (1 - f[0]) + at(1, 0, 1) * f[0];
        const double c11 = at(0, 1, 1) * (1 - f[0]) + at(1, 1, 1) * f[0];
        const double c0 = c00 * (1 - f[1]) + c10 * f[1];
        const double c1 = c01 * (1 - f[1]) + c11 * f[1];
        return c0 * (1 - f[2]) + c1 * f[2];
    }

    Color albedo_;
    double scale_ = 1.0;
    femto::Transform::Matrix to_local_{};
    int32_t res_[3] = {0, 0, 0};
    int64_t stride_[3] = {0, 0, 0};
    double bmin_[3] = {0, 0, 0}, bmax_[3] = {0, 0, 0}, to_grid_[3] = {0, 0, 0};
    std::vector<float> data_;
    double min_density_ = 0, max_density_ = 0;
    double min_sigma_ = 0, max_sigma_ = 0, residual_majorant_ = 0;
};

}  // namespace

FEMTO_PLUGIN(HeterogeneousMedium, femto::PluginKind::Medium, "heterogeneous",
             "Medium with densities from a voxel grid (Mitsuba .vol, float32); sigma_t = scale "
             "* density, sigma_s = albedo * sigma_t",
             {{"density", "string", "",
               "path of a Mitsuba gridvolume .vol file (float32, 1 channel) of densities per "
               "scene unit, relative to the scene file"},
              {"albedo", "color", "0.75", "single-scattering albedo sigma_s / sigma_t, in [0, 1]"},
              {"scale", "float", "1", "factor applied to the densities: sigma_t = scale * density"},
              {"to_world", "transform", "identity",
               "places the grid's bounding box (file coordinates) in the scene"}})
