// bitmap: an image texture (Mitsuba 3's `bitmap`), read through libfemto_io (OpenImageIO).
//
// Conventions (as Mitsuba): uv (0, 0) is the bottom-left corner of the image and (1, 1) the
// top-right, so v = 0 is the image's bottom row; texel (i, j) (j counted from the bottom) has
// its centre at ((i + 0.5) / width, (j + 0.5) / height). `nearest` takes the texel containing
// the point; `bilinear` interpolates the four nearest texel centres. `wrap_mode` decides what
// lies outside [0, 1): `repeat` tiles the image, `mirror` tiles it with every other copy
// mirrored, `clamp` repeats the edge texels. 8-bit images are sRGB-decoded to linear values
// unless `raw` is set; float images (EXR, PFM, HDR) are always linear. Negative or non-finite
// values (possible in float images) are read as 0, with a warning.
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "femto/image_io.h"
#include "femto/log.h"
#include "femto/plugin.h"
#include "femto/texture.h"
#include "femto/transform.h"

namespace {

enum class FilterType { Nearest, Bilinear };
enum class WrapMode { Repeat, Mirror, Clamp };

class Bitmap final : public femto::Texture {
public:
    explicit Bitmap(const femto::Properties& props) {
        const std::string filename = props.get_string("filename");
        raw_ = props.get_bool("raw", false);

        const std::string filter = props.get_string("filter_type", "bilinear");
        if (filter == "bilinear") {
            filter_ = FilterType::Bilinear;
        } else if (filter == "nearest") {
            filter_ = FilterType::Nearest;
        } else if (filter == "ewa" || filter == "trilinear") {
            // Mitsuba 0.6 filters that need MIP maps, which femto does not build.
            femto::log_warning(
                props.location_of("filter_type"),
                "bitmap: filter_type \"" + filter + "\" is not supported, using \"bilinear\"");
            filter_ = FilterType::Bilinear;
        } else {
            props.fail("filter_type",
                       "unknown filter_type \"" + filter + "\"; valid values: bilinear, nearest");
        }

        const std::string wrap = props.get_string("wrap_mode", "repeat");
        if (wrap == "repeat") {
            wrap_ = WrapMode::Repeat;
        } else if (wrap == "mirror") {
            wrap_ = WrapMode::Mirror;
        } else if (wrap == "clamp") {
            wrap_ = WrapMode::Clamp;
        } else {
            props.fail("wrap_mode",
                       "unknown wrap_mode \"" + wrap + "\"; valid values: repeat, mirror, clamp");
        }

        to_uv_ = props.get_transform("to_uv", femto::Transform());
        identity_ = to_uv_.is_identity();

        try {
            data_ = femto::io::read_image_rgb(filename, width_, height_, !raw_);
        } catch (const femto::SceneError& e) {
            props.fail("filename", e.message());  // it names the file and what is wrong
        }
        if (width_ <= 0 || height_ <= 0 ||
            data_.size() != static_cast<size_t>(width_) * static_cast<size_t>(height_) * 3)
            props.fail("filename", "image \"" + filename + "\" is empty or could not be decoded");
        clamp_negative_texels(props, filename);

        double sum[3] = {0, 0, 0};
        for (size_t i = 0; i < data_.size(); i += 3)
            for (int c = 0; c < 3; ++c) sum[c] += data_[i + c];
        const double n = static_cast<double>(width_) * height_;
        mean_ = femto::Color(static_cast<float>(sum[0] / n), static_cast<float>(sum[1] / n),
                             static_cast<float>(sum[2] / n));
    }

    femto::Color eval(const femto::Hit& hit) const override {
        float u = hit.uv.x, v = hit.uv.y;
        if (!identity_) {
            const femto::Vec3 p = to_uv_.point(femto::Vec3(u, v, 0.f));
            u = p.x;
            v = p.y;
        }
        if (!std::isfinite(u) || !std::isfinite(v)) return femto::Color(0.f);
        const double x = static_cast<double>(u) * width_;
        const double y = static_cast<double>(v) * height_;  // from the bottom row
        if (filter_ == FilterType::Nearest) return fetch(to_index(x), to_index(y));

        const double xs = x - 0.5, ys = y - 0.5;
        const double x0 = std::floor(xs), y0 = std::floor(ys);
        const float fx = static_cast<float>(xs - x0), fy = static_cast<float>(ys - y0);
        const int64_t i0 = to_index(x0), j0 = to_index(y0);
        const femto::Color c00 = fetch(i0, j0), c10 = fetch(i0 + 1, j0);
        const femto::Color c01 = fetch(i0, j0 + 1), c11 = fetch(i0 + 1, j0 + 1);
        return (c00 * (1.f - fx) + c10 * fx) * (1.f - fy) + (c01 * (1.f - fx) + c11 * fx) * fy;
    }

    femto::Color mean() const override { return mean_; }

    bool is_constant() const override { return width_ == 1 && height_ == 1; }

private:
    // Textures are reflectances and colours: a negative texel (float images can hold them)
    // would make negative radiance, a NaN or infinite one a NaN image. They are read as 0,
    // with a warning that says how many there were.
    void clamp_negative_texels(const femto::Properties& props, const std::string& filename) {
        size_t bad = 0;
        for (float& v : data_)
            if (!(v >= 0.f) || !std::isfinite(v)) {
                v = 0.f;
                ++bad;
            }
        if (bad > 0)
            femto::log_warning(props.location_of("filename"),
                               "bitmap: image \"" + filename + "\" has " + std::to_string(bad) +
                                   " negative or non-finite channel values; they are read as 0");
    }

    /// floor(x) as an integer; |x| is bounded first so the conversion cannot overflow (the
    /// wrap modes are periodic or clamp, so far-away texels are equivalent).
    static int64_t to_index(double x) {
        constexpr double kLimit = 0x1p52;
        if (x > kLimit) x = kLimit;
        if (x < -kLimit) x = -kLimit;
        return static_cast<int64_t>(std::floor(x));
    }

    int64_t wrap(int64_t i, int64_t n) const {
        switch (wrap_) {
            case WrapMode::Repeat: {
                const int64_t m = i % n;
                return m < 0 ? m + n : m;
            }
            case WrapMode::Mirror: {
                int64_t m = i % (2 * n);
                if (m < 0) m += 2 * n;
                return m < n ? m : 2 * n - 1 - m;
            }
            case WrapMode::Clamp:
                break;
        }
        return i < 0 ? 0 : (i >= n ? n - 1 : i);
    }

    /// Texel (i, j), j counted from the bottom row; the image is stored top row first.
    femto::Color fetch(int64_t i, int64_t j) const {
        const int64_t x = wrap(i, width_);
        const int64_t y = height_ - 1 - wrap(j, height_);
        const float* p = &data_[static_cast<size_t>((y * width_ + x) * 3)];
        return femto::Color(p[0], p[1], p[2]);
    }

    std::vector<float> data_;
    int width_ = 0, height_ = 0;
    bool raw_ = false;
    FilterType filter_ = FilterType::Bilinear;
    WrapMode wrap_ = WrapMode::Repeat;
    femto::Transform to_uv_;
    bool identity_ = true;
    femto::Color mean_;
};

}  // namespace

FEMTO_PLUGIN(Bitmap, femto::PluginKind::Texture, "bitmap",
             "Image texture (any format OpenImageIO reads; v = 0 is the bottom row)",
             {{"filename", "filename", "", "image file (relative to the scene file)"},
              {"raw", "boolean", "false",
               "use 8-bit values as they are instead of decoding sRGB (float images are always "
               "linear)"},
              {"filter_type", "string", "bilinear",
               "bilinear | nearest (Mitsuba 0.6's ewa and trilinear fall back to bilinear with a "
               "warning)"},
              {"wrap_mode", "string", "repeat", "repeat | mirror | clamp: the image outside [0,1)"},
              {"to_uv", "transform", "identity", "transform applied to the point (u, v, 0)"}})
