// femto public API: microfacet normal distributions (Beckmann and GGX, isotropic or
// anisotropic) with Smith's separable shadowing-masking term, for rough materials
// (roughconductor, roughplastic, and materials of your own).
//
// Conventions (as bsdf.h): directions are in the local shading frame, z = the macro-surface
// normal. D(m) is normalised over projected area (integral of D(m) m.z dm = 1).
//
// Sampling (as Mitsuba): with sample_visible the distribution of visible normals
// D_wi(m) = G1(wi, m) max(0, wi.m) D(m) / cos_i is sampled exactly: GGX by Heitz's 2018
// method, Beckmann by Heitz & d'Eon 2014 (stretch, sample the alpha = 1 slope distribution by a
// safeguarded Newton inversion of its CDF in the erf domain, rotate, unstretch). Without it,
// D(m) cos(theta_m) is sampled.
//
// Difference from Mitsuba: the Beckmann G1 is the exact Smith term 1 / (1 + Lambda(a)) with
// Lambda(a) = (exp(-a^2) / (a sqrt(pi)) - erfc(a)) / 2 and a = 1 / (alpha tan(theta)), where
// Mitsuba uses a rational fit (< 0.35% error). The exact term makes the visible-normal pdf
// integrate to exactly one, which the chi-square tests rely on.
#pragma once

#include <algorithm>
#include <string>

#include "femto/math.h"
#include "femto/properties.h"

namespace femto {

enum class MicrofacetType { Beckmann, GGX };

/// Smallest roughness a distribution keeps (smaller values are clamped to it, as Mitsuba does):
/// below it float precision no longer resolves the lobe.
inline constexpr float kMinMicrofacetAlpha = 1e-4f;

class Microfacet {
public:
    /// alpha_u / alpha_v: roughness along the tangent / bitangent (clamped to
    /// kMinMicrofacetAlpha).
    Microfacet(MicrofacetType type, float alpha_u, float alpha_v, bool sample_visible);

    MicrofacetType type() const { return type_; }
    float alpha_u() const { return au_; }
    float alpha_v() const { return av_; }
    bool sample_visible() const { return visible_; }

    /// Normal distribution D(m).
    float D(const Vec3& m) const;
    /// Smith's monodirectional shadowing-masking term for direction v and microfacet m.
    float G1(const Vec3& v, const Vec3& m) const;
    /// Density of sample() returning microfacet normal m for incident direction wi.
    float pdf(const Vec3& wi, const Vec3& m) const {
        if (visible_) return D(m) * G1(wi, m) * std::max(0.f, dot(wi, m)) / wi.z;
        return D(m) * m.z;
    }
    /// Samples a microfacet normal for wi (wi.z > 0). Returns false when sampling failed.
    bool sample(const Vec3& wi, Vec2 u, Vec3& m) const;

private:
    Vec3 sample_visible_ggx(const Vec3& wi, Vec2 u) const;
    Vec3 sample_visible_beckmann(const Vec3& wi, Vec2 u) const;
    Vec3 sample_full(Vec2 u) const;

    MicrofacetType type_;
    float au_, av_;
    bool visible_;
};

/// Reads `distribution` ("beckmann", the default, or "ggx"; case-insensitive). Other names,
/// including Mitsuba 0.6's "phong" and "as", are located errors naming the valid ones.
MicrofacetType read_microfacet_type(const Properties& props);

/// Reads a full microfacet description as Mitsuba 3's rough materials do: `distribution`,
/// either `alpha` (default 0.1) or both `alpha_u` and `alpha_v` (positive), `sample_visible`
/// (default true).
Microfacet read_microfacet(const Properties& props);

}  // namespace femto
