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
#include "femto/warp.h"

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

/// One sampled event at a path vertex, on top of the directional scattering of eval() and
/// sample(). A material with several kinds of event (e.g. elastic reflection or fluorescence,
/// thesis Fig. 5.16) picks one per vertex at random.
struct VertexEvent {
    /// Scattering delay Delta t_i (eq. 5.13), >= 0, in optical path length (scene units): how
    /// long the material holds the light before it leaves, e.g. a fluorescence lifetime.
    double delay = 0.0;
    /// When true, `transfer` weights the light: in the light direction, light leaving the vertex
    /// is transfer * (light arriving), applied on top of the eval()/sample() weights. The matrix
    /// includes 1 / (probability of choosing this event), so the estimator stays unbiased. A
    /// diagonal matrix is a per-channel weight (applied as cheaply as a BSDF colour);
    /// off-diagonal entries move energy between colour channels (fluorescence).
    bool transfers = false;
    ColorMatrix transfer;  ///< identity by default; only used when `transfers` is true
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

    /// Materials whose vertices do more than scatter directionally (delay and/or colour
    /// transfer, e.g. fluorescence) return true and implement sample_vertex_event(). The
    /// default (false) is an ordinary material: no delay, colour only in eval()/sample(), and
    /// no extra cost or random number per vertex.
    virtual bool has_vertex_event() const { return false; }
    /// Chooses what happens at this vertex from one uniform `u` in [0, 1) (hit.wi is set).
    /// The path tracer calls it once per vertex, before next-event estimation and sample(), and
    /// applies the event to everything leaving the vertex: the light connection and the
    /// continued path. Only called when has_vertex_event() is true.
    virtual VertexEvent sample_vertex_event(const Hit& /*hit*/, float /*u*/) const { return {}; }

    /// The share of light that crosses the surface straight through without interacting: the
    /// weight of its null lobe (1 for `null`, 1 - opacity for a `mask`, 0 for a material without
    /// one). Light tracing weighs its connections to the sensor by it at every surface they
    /// cross (trace_shadow()'s `through_masks`), the one way such an estimator sees light that
    /// passed a partly transparent surface last.
    virtual Color null_transmission(const Hit& /*hit*/) const {
        return Color(is_null() ? 1.f : 0.f);
    }

    /// False for a material whose f(wi, wo) differs from f(wo, wi), such as a measured BTF (its
    /// relief shadows the light and masks the view differently). eval() and sample() always
    /// take the camera's side as wi; paths traced from the lights go through eval_adjoint() and
    /// sample_adjoint() below, which swap the roles for such materials.
    virtual bool reciprocal() const { return true; }

    /// True when the material reads hit.footprint (the pixel footprint of a camera ray's first
    /// hit; prefiltering materials). The renderer gives camera rays their differentials only
    /// when some material in the scene does: the footprint costs ~8 % of a path tracer's
    /// instructions on a small scene.
    virtual bool uses_footprint() const { return false; }
    /// True when the material reads hit.dpdu (an oriented material: a BTF's frame, anisotropic
    /// roughness). Hits on other materials may skip it (a triangle's tangent solve costs ~5 %
    /// of a path tracer's instructions) and leave it zero, unless the ray carries a differential.
    virtual bool uses_tangent() const { return false; }
    /// Adaptive sampling (thesis ch. 3, Fig. 3.15): true when pixel_sample_share() can be
    /// below 1. The renderer then casts one ray through each pixel's centre before rendering.
    virtual bool adapts_sampling() const { return false; }
    /// The share s of the base sample count (spp_0) that a pixel whose centre ray first meets
    /// this material at `hit` needs: the renderer takes spp_p = max(1, ceil(s x spp_0))
    /// samples there. `hit.footprint` holds the pixel's footprint. Values outside (0, 1] are
    /// clamped. Only called when adapts_sampling() is true.
    virtual float pixel_sample_share(const Hit& /*hit*/) const { return 1.f; }

    bool has_delta_only() const { return (flags() & kBsdfSmooth) == 0; }
    bool is_null() const { return flags() == kBsdfNull; }
};

/// The weight of light that arrives at `hit` from local direction `wi` (toward the light) and
/// leaves toward `wo` (toward the camera's side), as light paths need it: f(wo, wi) |cos wo|,
/// the material evaluated with the camera's side first. eval(hit, wi, wo) for reciprocal
/// materials.
inline Color eval_adjoint(const Bsdf& bsdf, const Hit& hit, const Vec3& wi, const Vec3& wo) {
    if (bsdf.reciprocal()) return bsdf.eval(hit, wi, wo);
    const float cos_in = std::abs(wi.z);
    return cos_in > 0.f ? bsdf.eval(hit, wo, wi) * (std::abs(wo.z) / cos_in) : Color(0.f);
}

/// sample() for a light path arriving from `wi`: the direction from sample(), its non-delta
/// weight recomputed as eval_adjoint() / pdf for non-reciprocal materials.
inline BsdfSample sample_adjoint(const Bsdf& bsdf, const Hit& hit, const Vec3& wi, float u_lobe,
                                 Vec2 u) {
    BsdfSample s = bsdf.sample(hit, wi, u_lobe, u);
    if (!bsdf.reciprocal() && s.valid() && !(s.sampled_lobe & kBsdfDelta))
        s.weight = eval_adjoint(bsdf, hit, wi, s.wo) / s.pdf;
    return s;
}

/// Samples a Lambertian lobe of colour `albedo` (f = albedo / pi on the front side): a
/// cosine-weighted direction, weight = albedo; invalid when wi is behind the surface.
inline BsdfSample sample_lambertian(const Vec3& wi, Vec2 u, const Color& albedo) {
    BsdfSample s;
    if (wi.z <= 0.f) return s;
    s.wo = warp::square_to_cosine_hemisphere(u);
    s.pdf = warp::cosine_hemisphere_pdf(s.wo);
    if (!(s.pdf > 0.f)) {
        s.pdf = 0.f;
        return s;
    }
    s.eta = 1.f;
    s.sampled_lobe = kBsdfDiffuseReflection;
    s.weight = albedo;  // (albedo cos / pi) / (cos / pi)
    return s;
}

}  // namespace femto
