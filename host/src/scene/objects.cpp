// Base-class constructors of the plugin kinds whose common parameters the host reads.
#include <fmt/format.h>

#include "femto/film.h"
#include "femto/medium.h"
#include "femto/sampler.h"
#include "femto/sensor.h"
#include "femto/shape.h"
#include "scene/loader.h"

namespace femto {

namespace {
constexpr int64_t kMaxFilmSide = 1 << 16;
constexpr int64_t kMaxFilmPixels = int64_t(1) << 26;  // 8192 x 8192
}  // namespace

Transform read_to_world(const Properties& props) {
    const Transform t = props.get_transform("to_world", Transform());
    if (std::abs(t.det3()) < 1e-30)
        props.fail("to_world", "to_world is degenerate (it flattens space to a plane or a line)");
    return t;
}

Sensor::Sensor(const Properties& props) {
    to_world_ = read_to_world(props);
    auto films = props.objects(PluginKind::Film);
    auto samplers = props.objects(PluginKind::Sampler);
    if (films.size() > 1) props.fail("film", "a sensor takes at most one <film>");
    if (samplers.size() > 1) props.fail("sampler", "a sensor takes at most one <sampler>");
    film_ = std::static_pointer_cast<Film>(
        films.empty() ? detail::create_default(PluginKind::Film, "hdrfilm", props.location())
                      : films[0]);
    sampler_ = std::static_pointer_cast<Sampler>(
        samplers.empty()
            ? detail::create_default(PluginKind::Sampler, "independent", props.location())
            : samplers[0]);
    auto media = props.objects(PluginKind::Medium);
    if (media.size() > 1) props.fail("medium", "a sensor sits in at most one <medium>");
    if (!media.empty()) medium_ = std::static_pointer_cast<Medium>(media[0]);
}

Sampler::Sampler(const Properties& props) {
    const int64_t count = props.get_int("sample_count", 4);
    if (count <= 0 || count > int64_t(std::numeric_limits<uint32_t>::max()))
        props.fail("sample_count", "\"sample_count\" must be a positive integer below 2^32, got " +
                                       std::to_string(count));
    sample_count_ = uint32_t(count);
    seed_ = uint64_t(props.get_int("seed", 0));
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
    auto filters = props.objects(PluginKind::ReconstructionFilter);
    if (filters.size() > 1) props.fail("rfilter", "a film takes at most one <rfilter>");
    rfilter_ = std::static_pointer_cast<ReconstructionFilter>(
        filters.empty()
            ? detail::create_default(PluginKind::ReconstructionFilter, "gaussian", props.location())
            : filters[0]);
}

double Film::max_path_length() const { return std::numeric_limits<double>::infinity(); }

}  // namespace femto
