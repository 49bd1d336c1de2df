// femto public API: the scene as integrators see it (ray queries and light sampling).
#pragma once

#include <memory>
#include <vector>

#include "femto/emitter.h"
#include "femto/math.h"
#include "femto/sensor.h"
#include "femto/shape.h"
#include "femto/time.h"

namespace femto {

class Integrator;

struct Bounds3 {
    Vec3 min{kInfinity, kInfinity, kInfinity}, max{-kInfinity, -kInfinity, -kInfinity};
    void expand(const Vec3& p) {
        for (int i = 0; i < 3; ++i) {
            min[i] = std::min(min[i], p[i]);
            max[i] = std::max(max[i], p[i]);
        }
    }
    bool valid() const { return min.x <= max.x; }
    Vec3 center() const { return (min + max) * 0.5f; }
    float radius() const { return valid() ? 0.5f * length(max - min) : 0.f; }
};

class Scene {
public:
    Scene(std::shared_ptr<Integrator> integrator, std::shared_ptr<Sensor> sensor,
          std::vector<std::shared_ptr<Shape>> shapes,
          std::vector<std::shared_ptr<Emitter>> emitters);
    ~Scene();
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    /// Closest hit along `ray` within [tmin, tmax]; surfaces with a pure `null` material, no
    /// emitter and no media are invisible (a null surface that bounds a medium is hit, so
    /// that paths can track the medium they travel in). On a hit every field of `hit` is
    /// set, as on a fresh Hit: one Hit may serve all of a path's intersections. On a miss
    /// `hit` is left as it was.
    bool intersect(const Ray& ray, Hit& hit) const;
    /// True when anything blocks `ray` within [tmin, tmax]; `null` surfaces never block.
    bool occluded(const Ray& ray) const;

    /// All emitters (area emitters included).
    const std::vector<const Emitter*>& emitters() const { return emitter_list_; }
    /// The environment emitters (distant and not delta: constant, envmap), which rays that
    /// leave the scene see.
    const std::vector<const Emitter*>& environment() const { return environment_; }
    /// Density of sample_emitter() choosing direction `wi` on environment `emitter`, with the
    /// selection probability (MIS of rays that leave the scene).
    float pdf_environment(const Emitter& emitter, const Vec3& wi) const;
    /// The sphere around the shapes and the sensor that distant light is measured from.
    const SceneSphere& sphere() const { return sphere_; }
    /// Picks an emitter uniformly (u_select) and samples it for `ref`; the pdf and weight
    /// include the selection probability.
    EmitterSample sample_emitter(const Vec3& ref, float u_select, Vec2 u) const;
    /// Picks the emitter a light path starts from with one uniform number, as
    /// sample_emitter() does (uniformly); `pmf` is the probability of the pick. Null when the
    /// scene has no emitters.
    const Emitter* select_emitter(float u, float& pmf) const;
    /// Probability with which select_emitter() picks `emitter` (a light path's start, for MIS).
    float select_emitter_pmf(const Emitter& emitter) const;
    /// Density of sample_emitter() choosing `hit` on `emitter`, with the selection probability.
    float pdf_emitter(const Emitter& emitter, const Vec3& ref, const Hit& hit) const;

    const Sensor& sensor() const { return *sensor_; }
    Integrator& integrator() const { return *integrator_; }
    const std::vector<std::shared_ptr<Shape>>& shapes() const { return shapes_; }
    const Bounds3& bounds() const { return bounds_; }

    /// Rays traced so far by all threads (primary, bounce and shadow rays).
    uint64_t rays_traced() const;
    /// Earliest emission time of any emitter (PulseProfile::earliest), for cutting paths
    /// that can no longer reach a film's time window.
    double earliest_emission() const { return earliest_emission_; }
    /// The film's time window as paths see it (PathClock reads it). The renderer refreshes it
    /// before every pass, since a temporal filter's reach may change after its pilot pass.
    const TimeWindow& time_window() const { return time_window_; }
    /// Re-reads the film's window (Film::max_time()); called by the renderer.
    void refresh_time_window();
    /// True when a shape bounds a medium or the sensor or an emitter sits in one: integrators
    /// then track media along paths (volumetric path tracing).
    bool has_media() const { return has_media_; }

private:
    void place_distant_emitters();
    void check_media_precision();  // also sets has_media_

    struct Accel;
    std::unique_ptr<Accel> accel_;
    std::shared_ptr<Integrator> integrator_;
    std::shared_ptr<Sensor> sensor_;
    std::vector<std::shared_ptr<Shape>> shapes_;
    std::vector<std::shared_ptr<Emitter>> emitters_;
    std::vector<const Emitter*> emitter_list_;
    std::vector<const Emitter*> environment_;
    Bounds3 bounds_;
    SceneSphere sphere_;
    double earliest_emission_ = 0.0;
    TimeWindow time_window_;
    bool has_media_ = false;
};

}  // namespace femto
