// femto public API: participating media and phase functions (thesis ch. 5.6; Mitsuba's
// <medium> and <phase>).
//
// Conventions: directions are in world space and unit length; `wi` points back toward where
// the path came from (as for materials), `wo` is where it goes next. A phase function is a
// density over the sphere of `wo` (it integrates to 1); forward scattering (HG g > 0) favours
// wo = -wi. Coefficients are per scene unit of length and per colour channel.
//
// Time: light travels at c / eta inside a medium, so a distance d inside counts eta * d of
// optical path length (docs/units.md). Whether light refracts at the medium's boundary is the
// boundary material's business (a `null` or `dielectric` bsdf); the medium decides the speed.
#pragma once

#include <memory>

#include "femto/color.h"
#include "femto/math.h"
#include "femto/object.h"

namespace femto {

class Sampler;

class PhaseFunction : public Object {
public:
    PluginKind kind() const override { return PluginKind::Phase; }
    /// Phase function value p(wi -> wo), which is also the density of sample().
    virtual float eval(const Vec3& wi, const Vec3& wo) const = 0;
    /// Samples wo with density eval(wi, wo) from two uniforms (so the weight is exactly 1).
    virtual Vec3 sample(const Vec3& wi, Vec2 u) const = 0;
};

/// A point sampled along a ray inside a medium.
struct MediumSample {
    double distance = 0;  ///< along the ray from its origin
    Vec3 p;               ///< the point
    Color sigma_s;        ///< scattering coefficient there
    Color sigma_t;        ///< extinction coefficient there
};

class Medium : public Object {
public:
    PluginKind kind() const override { return PluginKind::Medium; }

    /// Index of refraction: the medium slows light to c / eta.
    double eta() const { return eta_; }
    const PhaseFunction& phase() const { return *phase_; }
    /// True when sigma_t and sigma_s are the same everywhere. transmittance() must then be
    /// exp(-sigma_t distance) per channel (exact), which the toolkit may compute itself
    /// (DistanceMixture::survival_is_transmittance()).
    virtual bool homogeneous() const = 0;
    /// Largest extinction anywhere in the medium over all channels (a majorant for tracking).
    virtual float majorant() const = 0;
    /// Coefficients at point p (world space); zero outside the medium's data.
    virtual Color sigma_t(const Vec3& p) const = 0;
    virtual Color sigma_s(const Vec3& p) const = 0;
    /// Transmittance exp(-integral of sigma_t) along `ray` (unit direction) from its origin over
    /// `distance`: exact for homogeneous media, an unbiased estimate (ratio tracking, drawing
    /// from `sampler`) otherwise.
    virtual Color transmittance(const Ray& ray, double distance, Sampler& sampler) const = 0;

    /// `eta` and `phase`: what the constructor reads, for the plugin schemas.
    static std::vector<ParamSpec> inherited_params();

protected:
    /// Reads `eta` (default 1) and the nested <phase> (default isotropic).
    explicit Medium(const class Properties& props);

    double eta_ = 1.0;
    std::shared_ptr<PhaseFunction> phase_;
};

}  // namespace femto
