// femto public API: materials (BSDFs).
//
// Conventions (as Mitsuba): directions are in the local shading frame (z = shading normal),
// `wi` points toward where the path came from (the camera side), `wo` is the sampled or
// queried outgoing direction. eval() returns f(wi, wo) * |cos(theta_o)|.
#pragma once

#include <cstdint>

#include "femto/color.h"
#include "femto/math.h"
#include "femto/object.h"
#include "femto/shape.h"

namespace femto {

enum BsdfFlags : uint32_t {
    kBsdfNull = 1u << 0,  ///< index-matched pass-through (the `null` material)
    kBsdfDiffuseReflection = 1u << 1,
    kBsdfGlossyReflection = 1u << 2,
    kBsdfDeltaReflection = 1u << 3,
    kBsdfDiffuseTransmission = 1u << 4,
    kBsdfGlossyTransmission = 1u << 5,
    kBsdfDeltaTransmission = 1u << 6,
    kBsdfDelta = kBsdfDeltaReflection | kBsdfDeltaTransmission | kBsdfNull,
    kBsdfSmooth = kBsdfDiffuseReflection | kBsdfGlossyReflection | kBsdfDiffuseTransmission |
                  kBsdfGlossyTransmission,
};

struct BsdfSample {
    Vec3 wo;
    float pdf = 0.f;            ///< solid-angle pdf (a discrete probability for delta lobes)
    float eta = 1.f;            ///< relative index of refraction crossed (1 for reflection)
    uint32_t sampled_lobe = 0;  ///< one of BsdfFlags
    Color weight;               ///< eval / pdf; black when sampling failed
    bool valid() const { return pdf > 0.f; }
};

class Bsdf : public Object {
public:
    PluginKind kind() const override { return PluginKind::Bsdf; }
    /// Union of the lobes this material has.
    virtual uint32_t flags() const = 0;
    /// Samples wo given wi; `u_lobe` picks a lobe, `u` the direction.
    virtual BsdfSample sample(const Hit& hit, const Vec3& wi, float u_lobe, Vec2 u) const = 0;
    /// f * |cos theta_o| for non-delta lobes (delta lobes evaluate to zero).
    virtual Color eval(const Hit& hit, const Vec3& wi, const Vec3& wo) const = 0;
    /// Density of sample() returning wo (non-delta lobes only).
    virtual float pdf(const Hit& hit, const Vec3& wi, const Vec3& wo) const = 0;

    /// Scattering delay (eq. 5.13) in optical path length (scene units): time the material
    /// holds the light before re-emitting it, e.g. a fluorescence lifetime. Sampled once per
    /// path vertex; 0 for ordinary materials.
    virtual double sample_delay(const Hit& /*hit*/, float /*u*/) const { return 0.0; }
    virtual bool has_delay() const { return false; }
    /// Colour transfer at a vertex for materials that move energy between colour channels
    /// (fluorescence): in the light direction, light leaving the vertex is M * (light arriving),
    /// applied on top of eval()/sample() weights. Only consulted when has_transfer() is true.
    virtual bool has_transfer() const { return false; }
    virtual ColorMatrix transfer(const Hit& /*hit*/) const { return {}; }

    bool has_delta_only() const { return (flags() & kBsdfSmooth) == 0; }
    bool is_null() const { return flags() == kBsdfNull; }
};

}  // namespace femto
