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
class Shape;

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
    /// The rays through pos + (1, 0) and pos + (0, 1) with the same `aperture` sample, as
    /// sample_ray() would return them (unit directions), for the pixel footprint of the camera
    /// ray's first hit (Hit::footprint). False when the sensor has none (the default: sensors
    /// without a film plane, such as meters); `out` is then left as it was.
    virtual bool sample_differential(Vec2 /*pos*/, Vec2 /*aperture*/,
                                     RayDifferential& /*out*/) const {
        return false;
    }

    /// False for sensors that no light path can reach by a connection (an orthographic
    /// camera: its rays are parallel, so a point sees it along one direction of measure
    /// zero); sample_direct() then always fails. Light tracers refuse such sensors.
    virtual bool connectable() const { return false; }
    /// The connection from `ref` to the sensor (`u` picks a point on a lens); invalid when ref
    /// is outside the field of view or the clipping range.
    virtual SensorSample sample_direct(const Vec3& /*ref*/, Vec2 /*u*/) const { return {}; }
    /// Solid-angle density with which sample_ray() at a uniformly drawn film position leaves in
    /// world direction `d` (unit); 0 outside the field of view, and 0 for a sensor with area
    /// (a direction alone has no density there).
    virtual float pdf_direction(const Vec3& /*d*/) const { return 0.f; }
    /// True when rays start anywhere on a surface (an irradiance meter), not at one point:
    /// sample_direct() then picks the point too. BDPT, whose MIS treats the sensor as one
    /// point, leaves its connections to such a sensor (strategies t = 1) out.
    virtual bool has_area() const { return false; }
    /// Factor on the radiance every camera ray brings back, applied by the renderer: 1 for
    /// sensors that measure radiance, pi for an irradiance meter (its cosine-distributed rays
    /// then estimate irradiance).
    virtual float ray_weight() const { return 1.f; }

    /// Called once, when the scene is built, for a sensor nested in a <shape> (Mitsuba 3's
    /// irradiancemeter); the shape is complete by then. The default refuses: most sensors do
    /// not measure on a surface.
    virtual void attach(const Shape& shape);
    /// True for a sensor that only works nested in a <shape>; a top-level one is refused.
    virtual bool needs_shape() const { return false; }

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
