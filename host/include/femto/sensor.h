// femto public API: sensors (cameras). A sensor owns its film and sampler.
#pragma once

#include <memory>

#include "femto/film.h"
#include "femto/math.h"
#include "femto/object.h"
#include "femto/properties.h"
#include "femto/sampler.h"
#include "femto/transform.h"

namespace femto {

class Medium;

/// A connection from a point in the scene to the sensor, for light paths the camera sees
/// (light tracing, BDPT's strategies that end on the sensor).
struct SensorSample {
    Vec3 p;               ///< the point on the sensor (a pinhole's centre)
    Vec3 wi;              ///< unit direction from the reference point toward p
    double distance = 0;  ///< from the reference point to p
    Vec2 pos;             ///< film position the connection lands on (pixels, as sample_ray())
    /// Importance the sensor sends back along the connection per unit of light, divided by the
    /// density of p: pdf_direction(-wi) / distance^2 for a pinhole. A splat of
    /// (light arriving at the reference point toward p) x weight, with samples_per_pixel x
    /// pixels light paths and Film::add_splat_weight(), estimates what camera samples do.
    float weight = 0;
    bool valid() const { return weight > 0; }
};

class Sensor : public Object {
public:
    PluginKind kind() const override { return PluginKind::Sensor; }

    /// Primary ray through film position `pos` (pixels, origin top-left, +x right, +y down);
    /// `aperture` is for lenses. Returns a ray with a unit direction.
    virtual Ray sample_ray(Vec2 pos, Vec2 aperture) const = 0;

    /// False for sensors that no light path can reach by a connection (an orthographic
    /// camera: its rays are parallel, so a point sees it along one direction of measure
    /// zero); sample_direct() then always fails. Light tracers refuse such sensors.
    virtual bool connectable() const { return false; }
    /// The connection from `ref` to the sensor (`u` picks a point on a lens); invalid when ref
    /// is outside the field of view or the clipping range.
    virtual SensorSample sample_direct(const Vec3& /*ref*/, Vec2 /*u*/) const { return {}; }
    /// Solid-angle density with which sample_ray() at a uniformly drawn film position leaves in
    /// world direction `d` (unit); 0 outside the field of view.
    virtual float pdf_direction(const Vec3& /*d*/) const { return 0.f; }

    Film& film() const { return *film_; }
    Sampler& sampler() const { return *sampler_; }
    const Transform& to_world() const { return to_world_; }
    /// The medium the sensor sits in (a nested <medium> or <ref>), or nullptr (vacuum).
    const Medium* medium() const { return medium_.get(); }

    /// The parameters the constructor reads, for the plugin schemas.
    static std::vector<ParamSpec> inherited_params();

protected:
    /// Reads `to_world`, the film and sampler children and the medium.
    explicit Sensor(const Properties& props);

    Transform to_world_;
    std::shared_ptr<Film> film_;
    std::shared_ptr<Sampler> sampler_;
    std::shared_ptr<Medium> medium_;
};

}  // namespace femto
