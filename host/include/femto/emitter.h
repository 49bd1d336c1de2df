// femto public API: light sources.
#pragma once

#include <algorithm>
#include <cmath>

#include "femto/color.h"
#include "femto/math.h"
#include "femto/object.h"
#include "femto/properties.h"
#include "femto/shape.h"

namespace femto {

/// When an emitter's light leaves it (docs/architecture.md §4), in optical path length (scene
/// units, time x c).
/// `delta`: all at `offset` (default 0); `box`: uniform in [offset, offset + width] (a long box
/// is continuous emission); `gaussian`: normal with mean `offset` and deviation `sigma`.
struct PulseProfile {
    enum class Shape { Delta, Box, Gaussian };
    Shape shape = Shape::Delta;
    double offset = 0, width = 0, sigma = 0;

    /// An emission time distributed as the profile, from one uniform number.
    double sample(float u) const;
    /// The probability density of emission at time t (+inf at a delta's offset).
    double pdf(double t) const;
    /// Earliest time with non-negligible emission (6 sigma for a Gaussian).
    double earliest() const;
    double mean() const;
    bool is_delta() const { return shape == Shape::Delta; }
};

/// The sphere around the scene (its shapes and the sensor position) that distant emitters
/// (directional, constant, envmap) measure their light from; Scene::sphere() holds it.
///
/// femto's time convention for distant light (docs/distant-light.md): the light arriving from
/// direction `wi` (pointing away from the scene) is a plane wave that crosses the plane tangent
/// to this sphere on the side it comes from, {x : dot(x - center, wi) = radius}, at its
/// emission time. It reaches a point x after the optical length radius - dot(x - center, wi)
/// (vacuum), which is >= 0 inside the sphere. Light paths from distant emitters start on that
/// plane; camera paths that leave the scene meet the wave there.
struct SceneSphere {
    Vec3 center;
    float radius = 1.f;

    /// Length from x to the plane wave's start plane along wi (clamped at a tiny positive
    /// length for points outside the sphere, e.g. an orthographic camera's ray origins).
    double plane_wave_distance(const Vec3& x, const Vec3& wi) const {
        const double along = double(x.x - center.x) * wi.x + double(x.y - center.y) * wi.y +
                             double(x.z - center.z) * wi.z;
        return std::max(double(radius) - along, 1e-6 * double(radius));
    }
    /// Where the light arriving at x from wi starts: x + wi * plane_wave_distance(x, wi), a
    /// point outside the scene's geometry (shadow rays toward it test the whole way out).
    Vec3 plane_wave_start(const Vec3& x, const Vec3& wi) const {
        return x + wi * float(plane_wave_distance(x, wi));
    }
    /// A point of the disk of radius `radius` on the start plane of direction wi, centred on
    /// the sphere's axis along wi, from a point `disk` of the unit disk: where light paths of
    /// a distant emitter start (area density 1 / (pi radius^2)).
    Vec3 plane_wave_disk(const Vec3& wi, Vec2 disk) const {
        return center + wi * radius + Frame(wi).to_world(Vec3(disk.x, disk.y, 0.f)) * radius;
    }
    /// Area density of plane_wave_disk()'s points.
    float disk_pdf() const { return float(1.0 / (M_PI * double(radius) * double(radius))); }
};

/// Result of sampling an emitter for direct lighting of a reference point.
struct EmitterSample {
    Vec3 p;              ///< point on the emitter
    Vec3 n;              ///< its normal (zero for point-like emitters)
    Vec3 wi;             ///< unit direction from the reference point toward the emitter
    float distance = 0;  ///< distance to p (distant emitters: to their plane wave's start)
    float pdf = 0;       ///< solid-angle pdf (1 for delta emitters); 0 = no contribution
    Color weight;        ///< incident radiance / pdf (irradiance for delta emitters)
    bool delta = false;  ///< true when no BSDF sample can hit this emitter (MIS weight 1)
    const class Emitter* emitter = nullptr;  ///< which emitter (set by Scene::sample_emitter)
};

/// Light leaving an emitter, sampled to start a light path (light tracing, BDPT).
struct EmissionSample {
    Vec3 p;                     ///< where the light leaves
    Vec3 n;                     ///< the surface normal there (zero for point-like emitters)
    Vec3 d;                     ///< unit direction it leaves in
    float p_error = 0.f;        ///< for a surface point: its offset scale (Hit::p_error)
    float pdf_position = 0.f;   ///< area density of p (1 for a delta position: point, spot)
    float pdf_direction = 0.f;  ///< solid-angle density of d at p (1 for a delta direction)
    /// eval_direction(d) / (pdf_position x pdf_direction): the light path's starting weight
    /// (power per unit of whatever the deltas leave).
    Color weight;
    bool delta_position = false;   ///< point, spot: the light leaves from a single point
    bool delta_direction = false;  ///< collimated: the light leaves in a single direction
    bool valid() const { return pdf_position > 0.f && pdf_direction > 0.f; }
};

class Emitter : public Object {
public:
    PluginKind kind() const override { return PluginKind::Emitter; }

    /// Samples incident light at `ref` (the shadow ray is the caller's job).
    virtual EmitterSample sample_direct(const Vec3& ref, Vec2 u) const = 0;
    /// Samples where and in which direction light leaves (a light path's first segment):
    /// `u_position` picks the point, `u_direction` the direction. The default fails (an
    /// emitter that light paths cannot start from; light tracers refuse it).
    virtual EmissionSample sample_emission(Vec2 /*u_position*/, Vec2 /*u_direction*/) const {
        return {};
    }
    /// What leaves point `at.p` (a sample_emission() result) per unit solid angle toward
    /// world direction `d`: radiance x |cos| for surfaces, intensity for point-like emitters;
    /// zero for a delta direction (no connection can follow it).
    virtual Color eval_direction(const EmissionSample& /*at*/, const Vec3& /*d*/) const {
        return {};
    }
    /// Densities with which sample_emission() returns point `at.p` and direction `d`.
    virtual void pdf_emission(const EmissionSample& /*at*/, const Vec3& /*d*/, float& pdf_position,
                              float& pdf_direction) const {
        pdf_position = pdf_direction = 0.f;
    }
    /// Solid-angle pdf that sample_direct(ref) picks the point `hit` on this emitter.
    virtual float pdf_direct(const Vec3& /*ref*/, const Hit& /*hit*/) const { return 0.f; }
    /// Radiance leaving the emitter's surface at `hit` toward world direction `w`.
    virtual Color eval(const Hit& /*hit*/, const Vec3& /*w*/) const { return {}; }
    /// True for point, spot, collimated and directional emitters (cannot be hit by a ray).
    virtual bool is_delta() const = 0;

    /// True for distant emitters (directional, constant, envmap): their light comes from
    /// outside the scene as plane waves (SceneSphere). Those that are not delta are
    /// environments: every ray that leaves the scene sees them (eval_environment()).
    virtual bool is_infinite() const { return false; }
    /// Environments: the radiance arriving from world direction `wi` (pointing away from the
    /// scene) along a ray that leaves the scene.
    virtual Color eval_environment(const Vec3& /*wi*/) const { return {}; }
    /// Environments: the solid-angle density with which sample_direct() picks direction `wi`
    /// (it does not depend on the reference point).
    virtual float pdf_environment(const Vec3& /*wi*/) const { return 0.f; }
    /// Called by the scene once its extent is known, before rendering: distant emitters place
    /// their plane waves and light-path starts by it.
    virtual void set_scene_sphere(const SceneSphere& /*sphere*/) {}

    /// Half-angle (radians) of the cone of directions in which `ref` sees the emitter: what
    /// a light sample stands for when a material prefilters over the light's directions
    /// (thesis ch. 3: the solid angle "subtended by a pixel and the light source"). The
    /// default covers every built-in kind: an area emitter's shape
    /// (Shape::subtended_half_angle()), pi for environments (light from every direction), 0
    /// for point-like and collimated emitters.
    virtual float subtended_half_angle(const Vec3& ref) const {
        if (shape_) return shape_->subtended_half_angle(ref);
        return is_infinite() && !is_delta() ? kPi : 0.f;
    }

    /// Area emitters are attached to the shape that holds them, by the host.
    void set_shape(const Shape* shape) { shape_ = shape; }
    const Shape* shape() const { return shape_; }

    /// The emission profile in time (the `pulse`, `pulse_width`, `pulse_sigma` and
    /// `time_offset` parameters every emitter takes).
    const PulseProfile& pulse() const { return pulse_; }
    /// The medium the emitter sits in (a nested <medium> or <ref>), or nullptr (vacuum); for
    /// area emitters, their shape's media apply instead.
    const Medium* medium() const { return medium_.get(); }

    /// The pulse parameters and the medium: what the constructor reads, for the schemas.
    static std::vector<ParamSpec> inherited_params();

protected:
    /// Reads the pulse parameters and the medium (inherited_params()).
    explicit Emitter(const Properties& props);

    /// Largest emitted value accepted per channel (radiance, intensity, irradiance, power). A
    /// float holds up to 3.4e38, but a render multiplies emission by path throughputs and sums
    /// many samples: values near that limit would write infinities into the outputs.
    static constexpr float kMaxEmission = 1e30f;
    /// Reads an emitted quantity: a located SceneError unless every channel is finite, >= 0
    /// and at most kMaxEmission.
    static Color read_emission(const Properties& props, const std::string& name, const Color& def);

    const Shape* shape_ = nullptr;
    PulseProfile pulse_;
    std::shared_ptr<class Medium> medium_;
};

}  // namespace femto
