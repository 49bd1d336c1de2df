// envmap: an environment of light from a latitude-longitude image (Mitsuba's `envmap`, 0.6 and
// 3), read through libfemto_io (OpenImageIO: EXR, HDR, PFM, PNG, ...).
//
// The mapping is Mitsuba 3's. In the emitter's frame (to_world), a direction d (pointing away
// from the scene) has u = atan2(d.x, -d.z) / 2 pi and v = acos(d.y) / pi: +y is up, the
// image's top row. Pixel column i sits at u = (i + 0.5) / width (wrapping around), pixel row j
// at v = j / (height - 1) (the first row at the zenith, the last at the nadir), and radiance is
// bilinear between them, times `scale`.
//
// Sampling (light samples and light paths) picks a cell between four pixels with probability
// proportional to their mean luminance times the cell's solid angle, then a uniform (u, v) in
// it: pdf = pmf / (cell's uv area x 2 pi^2 sin theta). Mitsuba 3 samples the bilinear
// interpolant itself (a hierarchical warp); the image converges to the same, the noise differs.
//
// Time (docs/distant-light.md): the light from each direction is a plane wave that crosses the
// plane tangent to the scene's sphere on the side it comes from (SceneSphere) at its emission
// time. Light paths start on the disk of the sphere's radius in that plane.
#include <cmath>
#include <string>
#include <vector>

#include "femto/emitter.h"
#include "femto/image_io.h"
#include "femto/log.h"
#include "femto/plugin.h"
#include "femto/transform.h"
#include "femto/warp.h"

namespace femto {
namespace {

// Mitsuba's luminance weights (Rec. 709), which its envmap samples by.
float luminance(const Color& c) { return 0.212671f * c[0] + 0.715160f * c[1] + 0.072169f * c[2]; }

class EnvironmentMap final : public Emitter {
public:
    explicit EnvironmentMap(const Properties& props) : Emitter(props) {
        const std::string filename = props.get_string("filename");
        try {
            data_ = io::read_image_rgb(filename, width_, height_, true);
        } catch (const SceneError& e) {
            props.fail("filename", e.message());  // it names the file and what is wrong
        }
        if (width_ < 2 || height_ < 3)
            props.fail("filename", "the environment map \"" + filename + "\" is " +
                                       std::to_string(width_) + "x" + std::to_string(height_) +
                                       " pixels; it must be at least 2x3 (as in Mitsuba)");
        check_pixels(props, filename);
        const double scale = props.get_float("scale", 1.0);
        if (!(scale >= 0) || !(scale <= kMaxEmission))
            props.fail("scale", "scale must be a finite number >= 0");
        scale_ = float(scale);
        const Transform to_world = read_to_world(props);
        to_world_ = to_world;
        to_local_ = to_world.inverse();
        read_ignored(props);
        build_distribution();
    }

    bool is_delta() const override { return false; }
    bool is_infinite() const override { return true; }
    void set_scene_sphere(const SceneSphere& sphere) override { sphere_ = sphere; }

    Color eval_environment(const Vec3& wi) const override {
        const Vec2 uv = to_uv(local_direction(wi));
        return lookup(uv) * scale_;
    }
    float pdf_environment(const Vec3& wi) const override {
        const Vec3 d = local_direction(wi);
        const float jacobian = uv_jacobian(d.y);
        return jacobian > 0.f ? pdf_uv(to_uv(d)) / jacobian : 0.f;  // the poles: a null set
    }

    EmitterSample sample_direct(const Vec3& ref, Vec2 u) const override {
        EmitterSample es;
        float pdf = 0.f;
        es.wi = sample_direction(u, pdf);
        if (!(pdf > 0)) return es;
        es.p = sphere_.plane_wave_start(ref, es.wi);
        es.n = -es.wi;
        es.distance = float(sphere_.plane_wave_distance(ref, es.wi));
        es.pdf = pdf;
        es.weight = eval_environment(es.wi) / pdf;
        return es;
    }

    // A direction the light comes from, then a point of the disk across the scene it crosses.
    EmissionSample sample_emission(Vec2 u_position, Vec2 u_direction) const override {
        EmissionSample es;
        float pdf = 0.f;
        const Vec3 wi = sample_direction(u_direction, pdf);
        if (!(pdf > 0)) return es;
        es.p = sphere_.plane_wave_disk(wi, warp::square_to_uniform_disk(u_position));
        es.n = -wi;
        es.d = -wi;
        es.pdf_position = sphere_.disk_pdf();
        es.pdf_direction = pdf;
        es.weight = eval_environment(wi) / (es.pdf_position * pdf);
        return es;
    }
    void pdf_emission(const EmissionSample&, const Vec3& d, float& pdf_position,
                      float& pdf_direction) const override {
        pdf_position = sphere_.disk_pdf();
        pdf_direction = pdf_environment(-d);
    }

private:
    Vec3 local_direction(const Vec3& wi) const { return normalize(to_local_.vector(wi)); }

    static Vec2 to_uv(const Vec3& d) {
        float u = std::atan2(d.x, -d.z) * kInvTwoPi;
        if (u < 0.f) u += 1.f;
        return {u, std::acos(clamp(d.y, -1.f, 1.f)) * kInvPi};
    }
    // d(solid angle) = 2 pi^2 sin(theta) du dv.
    static float uv_jacobian(float cos_theta) {
        return 2.f * kPi * kPi * safe_sqrt(1.f - cos_theta * cos_theta);
    }

    // Continuous pixel coordinates of uv: x in [0, width) with column i at i + 0.5 shifted to
    // i, y in [0, height - 1].
    void to_pixels(Vec2 uv, float& x, float& y) const {
        x = uv.x * float(width_) - 0.5f;
        x -= float(width_) * std::floor(x / float(width_));
        if (!(x < float(width_))) x = 0.f;
        y = clamp(uv.y * float(height_ - 1), 0.f, float(height_ - 1));
    }
    Color pixel(int i, int j) const {
        const float* p = &data_[(size_t(j) * size_t(width_) + size_t(i % width_)) * 3];
        return Color(p[0], p[1], p[2]);
    }
    Color lookup(Vec2 uv) const {
        float x, y;
        to_pixels(uv, x, y);
        const int i = std::min(int(x), width_ - 1), j = std::min(int(y), height_ - 2);
        const float fx = x - float(i), fy = y - float(j);
        return (pixel(i, j) * (1.f - fx) + pixel(i + 1, j) * fx) * (1.f - fy) +
               (pixel(i, j + 1) * (1.f - fx) + pixel(i + 1, j + 1) * fx) * fy;
    }

    // Cells: column i spans pixels i..i+1 (x in [i, i+1)), row j spans pixel rows j..j+1.
    int cells_x() const { return width_; }
    int cells_y() const { return height_ - 1; }
    void build_distribution() {
        const int nx = cells_x(), ny = cells_y();
        conditional_.assign(size_t(ny) * size_t(nx + 1), 0.f);
        marginal_.assign(size_t(ny) + 1, 0.f);
        std::vector<double> row_sum(size_t(ny), 0.0);
        for (int j = 0; j < ny; ++j) {
            const double band = std::cos(M_PI * j / ny) - std::cos(M_PI * (j + 1) / ny);
            std::vector<double> w(static_cast<size_t>(nx), 0.0);
            for (int i = 0; i < nx; ++i) {
                const double lum =
                    0.25 * (double(luminance(pixel(i, j))) + luminance(pixel(i + 1, j)) +
                            luminance(pixel(i, j + 1)) + luminance(pixel(i + 1, j + 1)));
                w[size_t(i)] = lum * band;
                row_sum[size_t(j)] += w[size_t(i)];
            }
            normalize_cdf(w, &conditional_[size_t(j) * size_t(nx + 1)]);
        }
        normalize_cdf(row_sum, marginal_.data());
    }
    // Writes the normalized CDF (n + 1 entries) of weights w; all-zero weights give a uniform
    // one (such a row or map is never picked or emits nothing).
    static void normalize_cdf(const std::vector<double>& w, float* cdf) {
        double total = 0.0;
        for (double x : w) total += x;
        double acc = 0.0;
        cdf[0] = 0.f;
        for (size_t k = 0; k < w.size(); ++k) {
            acc += total > 0 ? w[k] : 1.0;
            cdf[k + 1] = float(acc / (total > 0 ? total : double(w.size())));
        }
        cdf[w.size()] = 1.f;
    }
    const float* row_cdf(int j) const { return &conditional_[size_t(j) * size_t(cells_x() + 1)]; }

    // A world direction toward the environment, and its solid-angle density.
    Vec3 sample_direction(Vec2 u, float& pdf) const {
        if (!(marginal_total_positive())) return pdf = 0.f, Vec3();
        float uy = u.y, ux = u.x;
        const int j = int(warp::sample_discrete_cdf(marginal_.data(), uint32_t(cells_y()), uy));
        const int i = int(warp::sample_discrete_cdf(row_cdf(j), uint32_t(cells_x()), ux));
        // Pixel coordinates back to uv: x = i + ux is u * width - 0.5.
        Vec2 uv{(float(i) + ux + 0.5f) / float(width_), (float(j) + uy) / float(cells_y())};
        if (uv.x >= 1.f) uv.x -= 1.f;
        const float theta = uv.y * kPi, phi = uv.x * 2.f * kPi;
        const Vec3 d(std::sin(phi) * std::sin(theta), std::cos(theta),
                     -std::cos(phi) * std::sin(theta));
        const Vec3 world = normalize(to_world_.vector(d));
        pdf = pdf_environment(world);
        return world;
    }
    // Density of sample_direction() in uv: the cell's probability over its uv area.
    float pdf_uv(Vec2 uv) const {
        float x, y;
        to_pixels(uv, x, y);
        const int i = std::min(int(x), cells_x() - 1), j = std::min(int(y), cells_y() - 1);
        const float pmf =
            (marginal_[size_t(j) + 1] - marginal_[size_t(j)]) * (row_cdf(j)[i + 1] - row_cdf(j)[i]);
        return pmf * float(cells_x()) * float(cells_y());
    }
    bool marginal_total_positive() const { return any_light_; }

    // NaN and infinite pixels are errors (they would poison every render); negative ones (float
    // images can hold them) are read as 0 with a warning, as the bitmap texture does.
    void check_pixels(const Properties& props, const std::string& filename) {
        size_t negative = 0;
        for (size_t k = 0; k < data_.size(); ++k) {
            float& v = data_[k];
            if (!std::isfinite(v)) {
                const size_t pixel = k / 3;
                props.fail("filename", "the environment map \"" + filename +
                                           "\" has a non-finite value at "
                                           "pixel (" +
                                           std::to_string(pixel % size_t(width_)) + ", " +
                                           std::to_string(pixel / size_t(width_)) + ")");
            }
            if (v < 0.f) v = 0.f, ++negative;
            any_light_ = any_light_ || v > 0.f;
        }
        if (negative > 0)
            log_warning(props.location_of("filename"),
                        "envmap: image \"" + filename + "\" has " + std::to_string(negative) +
                            " negative channel values; they are read as 0");
    }

    // Mitsuba parameters that change nothing in femto, accepted with a note.
    static void read_ignored(const Properties& props) {
        if (props.get_bool("mis_compensation", false))
            log_note(props.location_of("mis_compensation"),
                     "femto ignores mis_compensation=true: it samples the map by luminance (a "
                     "compensated density would starve light paths of dim directions)");
        if (props.has("gamma")) {
            props.get_float("gamma");  // read: a Mitsuba file that sets it loads unchanged
            log_note(props.location_of("gamma"),
                     "femto ignores gamma: 8-bit images are decoded as sRGB, float images are "
                     "linear");
        }
        if (props.has("cache")) props.get_bool("cache");  // 0.6's MIP-map cache: nothing to do
    }

    std::vector<float> data_;  // linear RGB, rows from the top (zenith)
    int width_ = 0, height_ = 0;
    float scale_ = 1.f;
    bool any_light_ = false;
    Transform to_world_, to_local_;
    std::vector<float> marginal_, conditional_;
    SceneSphere sphere_;
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::EnvironmentMap, femto::PluginKind::Emitter, "envmap",
             "Environment of light from a latitude-longitude image",
             {{"filename", "filename", "", "latitude-longitude radiance image (+y up, as Mitsuba)"},
              {"scale", "float", "1", "factor applied to the image's radiance"},
              {"to_world", "transform", "identity", "orientation of the map"},
              {"mis_compensation", "bool", "false", "Mitsuba 3's option; accepted, ignored"},
              {"gamma", "float", "", "Mitsuba 0.6's gamma override; accepted, ignored"},
              {"cache", "bool", "", "Mitsuba 0.6's MIP-map cache; accepted, ignored"}})
