// femto public API: the time rules of a camera path, in one type (design section 4,
// docs/units.md, thesis eq. 5.11-5.16).
//
// An integrator that follows a path from the camera owns one PathClock per camera sample and
// lets it do every time computation, so that each contribution lands at the right time and
// every integrator follows the same rules:
//   - time is optical length: a segment of length d at refractive index eta takes eta * d
//     (travel_to()); d is measured between the vertices' actual positions, never from a
//     spawned ray's origin, which starts a little off its surface (docs/precision.md);
//   - materials and phase functions may hold light at a vertex (fluorescence): delay();
//   - the first scattering vertex (a surface that is not `null`, or a medium vertex) fixes the
//     sensor distance, which world-time films subtract (eq. 4.1) and store as the pixel's depth
//     (reach_vertex());
//   - light leaves an emitter at the time its pulse says: record() draws that emission time
//     and adds the radiance at the path's time plus the shadow connection's optical length;
//   - a path whose time is past the window's cut can no longer reach the film (expired()).
// The window comes from the scene (Scene::time_window(), refreshed by the renderer before each
// pass), never from the film per sample.
#pragma once

#include <algorithm>
#include <cmath>

#include "femto/emitter.h"
#include "femto/film.h"
#include "femto/sampler.h"
#include "femto/scene.h"
#include "femto/time.h"

namespace femto {

class LightClock;

class PathClock {
public:
    /// Starts a camera path at the sensor point `origin` (the camera ray's origin) at time 0;
    /// contributions go to `out`.
    PathClock(const Scene& scene, ContributionList& out, const Vec3& origin)
        : window_(scene.time_window()), sphere_(&scene.sphere()), out_(out), position_(origin) {}

    /// Optical length travelled so far plus the vertices' delays (scene units).
    double time() const { return time_; }
    const TimeWindow& window() const { return window_; }
    /// Optical length the path may still travel before nothing it carries can reach the film
    /// (infinite with a steady film; negative once expired).
    double remaining() const { return cut() - time_; }
    /// True when the path is past the window: no light it could still carry arrives in time.
    bool expired() const { return time_ > cut(); }

    /// Where the path is: its latest vertex (or the sensor point).
    const Vec3& position() const { return position_; }
    /// The path moves to its next vertex `p` (a surface hit's Hit::p, a point in a medium)
    /// through a medium of refractive index `eta`: the time grows by eta * |p - position()|.
    void travel_to(const Vec3& p, double eta) {
        time_ += distance_between(position_, p) * eta;
        position_ = p;
    }
    /// A vertex holds the light for `delay` (VertexEvent::delay).
    void delay(double delay) { time_ += delay; }
    /// The path scatters here (a surface that is not `null`, or a medium vertex); the first
    /// such vertex sets the camera sample's sensor distance.
    void reach_vertex() {
        if (out_.sensor_distance() < 0) out_.set_sensor_distance(time_);
    }

    /// Adds radiance `radiance` emitted by `emitter` that reaches the current vertex over a
    /// further optical length `extra` (a shadow connection; 0 for an emitter the path hit).
    /// The emission time is drawn from the emitter's pulse (one number from `sampler` unless
    /// the pulse is a delta), even when the radiance is black, so that the random stream does
    /// not depend on the value.
    void record(const Color& radiance, const Emitter& emitter, Sampler& sampler,
                double extra = 0.0) const {
        const double emitted = emission_time(emitter, sampler);
        out_.add(radiance, time_ + extra + emitted);
    }
    /// Adds radiance `radiance` of a distant emitter arriving at the current vertex from
    /// direction `wi` through a medium of refractive index `eta` (a ray that left the scene):
    /// the light travelled from its plane wave's start (SceneSphere::plane_wave_distance).
    void record_distant(const Color& radiance, const Emitter& emitter, Sampler& sampler,
                        const Vec3& wi, double eta) const {
        record(radiance, emitter, sampler, sphere_->plane_wave_distance(position_, wi) * eta);
    }
    /// Whether light that a light subpath brought to its vertex (`light`, its clock) can join
    /// this path over a connection of at least `distance` and still arrive within the window
    /// (check it before tracing the connection: bidirectional integrators).
    bool arrives_in_time(const LightClock& light, double distance) const;
    /// Adds `radiance` that a light subpath brought to its vertex (`light`) and that reaches the
    /// current vertex over a connection of optical length `connection`.
    void record(const Color& radiance, const LightClock& light, double connection) const;
    /// Adds `radiance` that a photon brought to the current vertex (a density estimate), the
    /// photon having reached its own vertex at `photon_time` (its LightClock::time() there,
    /// emission time included), spread in time by the estimate's kernel `kernel`.
    void record(const Color& radiance, double photon_time, TimeKernel kernel) const {
        out_.add(radiance, time_ + photon_time, kernel);
    }
    /// Adds a value measured at the current vertex that no emitter sent (ambient occlusion, a
    /// debugging quantity): it is recorded at the clock's time.
    void record(const Color& value) const { out_.add(value, time_); }
    /// When `emitter`'s light leaves it: its pulse's offset, or a sample of its profile.
    static double emission_time(const Emitter& emitter, Sampler& sampler) {
        const PulseProfile& pulse = emitter.pulse();
        return pulse.is_delta() ? pulse.offset : pulse.sample(sampler.next_1d());
    }

private:
    // In world time the cut moves with the sensor distance, known from the first vertex on.
    double cut() const { return window_.path_cut(out_.sensor_distance()); }

    TimeWindow window_;
    const SceneSphere* sphere_;
    ContributionList& out_;
    Vec3 position_;
    double time_ = 0.0;
};

/// The time rules of a light path (light tracing, a bidirectional integrator's light subpaths):
/// PathClock's, from the other end. The path starts when its emitter's pulse says; each segment
/// adds eta x its length between actual vertices, each vertex its delay; a connection to the
/// sensor adds its optical length, which is also the splat's sensor distance (the segment
/// world-time films remove, eq. 4.1).
class LightClock {
public:
    /// Starts a light path at `origin` on `emitter`, drawing its emission time (one number
    /// from `sampler` unless the pulse is a delta).
    LightClock(const Scene& scene, const Emitter& emitter, const Vec3& origin, Sampler& sampler)
        : window_(scene.time_window()),
          position_(origin),
          time_(PathClock::emission_time(emitter, sampler)) {}

    /// Emission time plus the optical length travelled and the vertices' delays.
    double time() const { return time_; }
    const Vec3& position() const { return position_; }
    /// The path moves to its next vertex `p` through a medium of refractive index `eta`.
    void travel_to(const Vec3& p, double eta) {
        time_ += distance_between(position_, p) * eta;
        position_ = p;
    }
    /// A vertex holds the light for `delay` (VertexEvent::delay).
    void delay(double delay) { time_ += delay; }
    /// True when nothing the path carries can reach the film any more: past the window's end
    /// (a connection to the sensor only adds time) or, in world time, past its world end (a
    /// light path's world time is its own time: the connection is the sensor segment).
    bool expired() const { return time_ > cut(); }
    /// Whether light leaving the current vertex over at least `distance` more optical length
    /// still arrives within the window (check it before tracing a connection).
    bool arrives_in_time(double distance) const {
        // In world time the connection is the sensor segment, which the film removes.
        return time_ + (std::isfinite(window_.world_end) ? 0.0 : distance) <= cut();
    }
    /// Adds `radiance` that reaches the sensor at film position `pos` from the current vertex
    /// over a connection of optical length `connection` (ShadowConnection::optical_length).
    void record(SplatList& out, Vec2 pos, const Color& radiance, double connection) const {
        out.add({pos, radiance, out.sample_index(), time_ + connection, connection});
    }

private:
    double cut() const { return window_.light_cut(); }

    TimeWindow window_;
    Vec3 position_;
    double time_;
};

inline bool PathClock::arrives_in_time(const LightClock& light, double distance) const {
    // The light subpath's time includes its emission time: the cut is the window's own end.
    return time_ + distance + light.time() <= cut() + window_.earliest_emission;
}

inline void PathClock::record(const Color& radiance, const LightClock& light,
                              double connection) const {
    out_.add(radiance, time_ + connection + light.time());
}

}  // namespace femto
