// femto public API: light sources.
#pragma once

#include "femto/color.h"
#include "femto/math.h"
#include "femto/object.h"
#include "femto/shape.h"

namespace femto {

/// Result of sampling an emitter for direct lighting of a reference point.
struct EmitterSample {
    Vec3 p;              ///< point on the emitter
    Vec3 n;              ///< its normal (zero for point-like emitters)
    Vec3 wi;             ///< unit direction from the reference point toward the emitter
    float distance = 0;  ///< distance to p (infinite for distant emitters)
    float pdf = 0;       ///< solid-angle pdf (1 for delta emitters); 0 = no contribution
    Color weight;        ///< incident radiance / pdf (irradiance for delta emitters)
    bool delta = false;  ///< true when no BSDF sample can hit this emitter (MIS weight 1)
};

class Emitter : public Object {
public:
    PluginKind kind() const override { return PluginKind::Emitter; }

    /// Samples incident light at `ref` (the shadow ray is the caller's job).
    virtual EmitterSample sample_direct(const Vec3& ref, Vec2 u) const = 0;
    /// Solid-angle pdf that sample_direct(ref) picks the point `hit` on this emitter.
    virtual float pdf_direct(const Vec3& /*ref*/, const Hit& /*hit*/) const { return 0.f; }
    /// Radiance leaving the emitter's surface at `hit` toward world direction `w`.
    virtual Color eval(const Hit& /*hit*/, const Vec3& /*w*/) const { return {}; }
    /// True for point, spot and collimated emitters (cannot be hit by a ray).
    virtual bool is_delta() const = 0;

    /// Area emitters are attached to the shape that holds them, by the host.
    void set_shape(const Shape* shape) { shape_ = shape; }
    const Shape* shape() const { return shape_; }

protected:
    const Shape* shape_ = nullptr;
};

}  // namespace femto
