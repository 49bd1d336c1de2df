// Base-class constructors of the plugin kinds whose common parameters the host reads.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "femto/film.h"
#include "femto/medium.h"
#include "femto/sampler.h"
#include "femto/sensor.h"
#include "femto/shape.h"

namespace femto {

namespace {
constexpr int64_t kMaxFilmSide = 1 << 16;
constexpr int64_t kMaxFilmPixels = int64_t(1) << 26;  // 8192 x 8192
}  // namespace

Transform read_to_world(const Properties& props) {
    const Transform t = props.get_transform("to_world", Transform());
    if (std::abs(t.det3()) < 1e-30)
        props.fail("to_world", "to_world is degenerate (it flattens space to a plane or a line)");
    if (const Vec3 origin = t.point(Vec3(0.f)); !within_scene_range(origin))
        props.fail("to_world", outside_scene_range("to_world's origin", origin));
    return t;
}

std::vector<ParamSpec> Sensor::inherited_params() {
    return inherit_params(
        Object::inherited_params(), "Sensor",
        {{"to_world", "transform", "identity", "camera-to-world transform"},
         {"film", "film", "hdrfilm", "the film (nested)"},
         {"sampler", "sampler", "independent", "the sampler (nested)"},
         {"medium", "medium", "", "medium the sensor sits in (nested <medium> or <ref>)"}});
}

Sensor::Sensor(const Properties& props) {
    to_world_ = read_to_world(props);
    film_ = std::static_pointer_cast<Film>(props.child(PluginKind::Film, "hdrfilm"));
    sampler_ = std::static_pointer_cast<Sampler>(props.child(PluginKind::Sampler, "independent"));
    medium_ = std::static_pointer_cast<Medium>(props.child(PluginKind::Medium));
}

void Sensor::attach(const Shape&) {
    throw SceneError(location(), "a <sensor type=\"" + type_name() +
                                     "\"> cannot be nested in a <shape>: only irradiancemeter "
                                     "measures on a surface; put this sensor in <scene>");
}

std::vector<ParamSpec> Sampler::inherited_params() {
    return inherit_params(Object::inherited_params(), "Sampler",
                          {{"sample_count", "integer", "4", "samples per pixel (> 0)"},
                           {"seed", "integer", "0", "seed offset, combined with the render seed"}});
}

Sampler::Sampler(const Properties& props) {
    const int64_t count = props.get_int("sample_count", 4);
    if (count <= 0 || count > int64_t(std::numeric_limits<uint32_t>::max()))
        props.fail("sample_count", "\"sample_count\" must be a positive integer below 2^32, got " +
                                       std::to_string(count));
    sample_count_ = uint32_t(count);
    seed_ = uint64_t(props.get_int("seed", 0));
}

std::vector<ParamSpec> Film::inherited_params() {
    return inherit_params(Object::inherited_params(), "Film",
                          {{"width", "integer", "768", "image width in pixels"},
                           {"height", "integer", "576", "image height in pixels"},
                           {"rfilter", "rfilter", "gaussian", "reconstruction filter (nested)"}});
}

Film::Film(const Properties& props) {
    const int64_t w = props.get_int("width", 768), h = props.get_int("height", 576);
    if (w < 1 || w > kMaxFilmSide)
        props.fail("width", fmt::format("width must be in [1, {}], got {}", kMaxFilmSide, w));
    if (h < 1 || h > kMaxFilmSide)
        props.fail("height", fmt::format("height must be in [1, {}], got {}", kMaxFilmSide, h));
    if (w * h > kMaxFilmPixels)
        props.fail("width",
                   fmt::format("{}x{} pixels is more than femto's limit of 2^26 pixels", w, h));
    width_ = int(w);
    height_ = int(h);
    rfilter_ = std::static_pointer_cast<ReconstructionFilter>(
        props.child(PluginKind::ReconstructionFilter, "gaussian"));
}

void Film::add_splat_weight(double) {
    throw SceneError(location(), type_name() + " does not accept splats from a light tracer");
}

std::vector<Accumulator> Film::accumulators() {
    throw SceneError(location(), type_name() +
                                     " cannot take part in a distributed (MPI) render: it does "
                                     "not list its running totals (Film::accumulators())");
}

void Film::prepare_aovs(const std::vector<std::string>& names, const Object& integrator) {
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    throw SceneError(integrator.location(),
                     fmt::format("the {} integrator writes AOV channels ({}), which the {} film "
                                 "does not record; use a steady film (hdrfilm)",
                                 integrator.type_name(), list, type_name()));
}

std::vector<double> Film::filter_weight_integrals(bool horizontal) const {
    // Midpoint rule over each pixel within the filter's reach, as camera samples jittered
    // uniformly within their pixels would weigh the pixel in expectation.
    constexpr int kSteps = 256;
    const int n = horizontal ? width_ : height_;
    const float r = rfilter_->radius();
    std::vector<double> integral(size_t(n), 0.0);
    for (int i = 0; i < n; ++i) {
        const double centre = i + 0.5;
        const int k0 = std::max(0, int(std::floor(centre - r))),
                  k1 = std::min(n - 1, int(std::ceil(centre + r)));
        double sum = 0;
        for (int k = k0; k <= k1; ++k)
            for (int j = 0; j < kSteps; ++j)
                sum += rfilter_->eval(float(k + (j + 0.5) / kSteps - centre));
        integral[size_t(i)] = sum / kSteps;
    }
    return integral;
}

double Film::max_time() const { return std::numeric_limits<double>::infinity(); }
double Film::max_world_time() const { return std::numeric_limits<double>::infinity(); }

}  // namespace femto
