#include "femto/density_estimation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "femto/error.h"
#include "femto/medium.h"
#include "femto/sensor.h"
#include "femto/tfilter.h"

namespace femto {

ProgressiveBandwidths read_progressive_schedule(const Properties& props, const std::string& prefix,
                                                double alpha, double beta_t, int dims) {
    ProgressiveBandwidths schedule{alpha, beta_t, dims};
    const std::string a = prefix + "alpha", b = prefix + "beta_t";
    schedule.alpha = props.get_float(a, alpha);
    if (!(schedule.alpha > 0.0 && schedule.alpha < 1.0))
        props.fail(a, a + " must lie in (0, 1): the share of each pass's bandwidth reduction "
                          "kept (eq. 5.58)");
    schedule.beta_t = props.get_float(b, beta_t);
    if (!(schedule.beta_t >= 0.0 && schedule.beta_t <= 1.0))
        props.fail(b, b + " must lie in [0, 1] (beta_R = 1 - beta_t, eq. 5.58)");
    return schedule;
}

double read_optional_bandwidth(const Properties& props, const std::string& name) {
    if (!props.has(name)) return 0.0;
    const double v = props.get_float(name);
    if (!(v > 0.0) || !std::isfinite(v))
        props.fail(name, fmt::format("{} must be positive and finite (scene units)", name));
    return v;
}

double default_initial_radius(const Scene& scene) {
    const Film& film = scene.sensor().film();
    const Vec2 centre{0.5f * float(film.width()), 0.5f * float(film.height())};
    const Ray a = scene.sensor().sample_ray(centre, {0.5f, 0.5f});
    const Ray b = scene.sensor().sample_ray(centre + Vec2{1.f, 0.f}, {0.5f, 0.5f});
    const double extent = scene.bounds().radius();
    const bool sized = extent > 0 && std::isfinite(extent);
    Hit hit;
    double distance = scene.intersect(a, hit) ? double(hit.t) : kInfinity;
    if (const Medium* medium = scene.sensor().medium(); medium && medium->majorant() > 0.f)
        distance = std::min(distance, 1.0 / double(medium->majorant()));
    if (!std::isfinite(distance)) return sized ? extent / 500.0 : 1.0;
    const double footprint = double(length(a.at(float(distance)) - b.at(float(distance))));
    if (!sized) return 3.0 * footprint;
    return std::clamp(3.0 * footprint, 1e-6 * extent, extent / 50.0);
}

double default_initial_bandwidth(const Scene& scene) {
    const auto* film = dynamic_cast<const TimeResolvedFilm*>(&scene.sensor().film());
    return film ? 2.0 * film->grid().bin_width : 1.0;
}

void require_histogram_film(const Scene& scene, const std::string& integrator) {
    const auto* film = dynamic_cast<const TimeResolvedFilm*>(&scene.sensor().film());
    if (film && !film->tfilter().is_histogram())
        throw SceneError(film->tfilter().location(),
                         fmt::format("{} smooths time with its own kernel (temporal_kernel, "
                                     "initial_bandwidth); the film must not smooth a second "
                                     "time: use <tfilter type=\"histogram\"/> instead of \"{}\"",
                                     integrator, film->tfilter().type_name()));
}

}  // namespace femto
