// femto public API: light sources.
#pragma once

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

/// Result of sampling an emitter for direct lighting of a reference point.
struct EmitterSample {
    Vec3 p;              ///< point on the emitter
    Vec3 n;              ///< its normal (zero for point-like emitters)
    Vec3 wi;             ///< unit direction from the reference point toward the emitter
    float distance = 0;  ///< distance to p (infinite for distant emitters)
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
    /// True for point, spot and collimated emitters (cannot be hit by a ray).
    virtual bool is_delta() const = 0;

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
