// femto public API: Fresnel reflectance of smooth dielectric and conductor interfaces, and the
// named indices of refraction that materials accept (Mitsuba's tables).
//
// Conventions (as bsdf.h): cosines are taken in the local shading frame, against +z; `eta` is
// always relative: the index of the interior (the side -z points into) over that of the
// exterior. The lookups return nothing for an unknown name, so that a plugin can report it
// with Properties::fail(), listing the valid names. Tested directly in
// tests/unit/test_fresnel.cpp and through the materials in tests/unit/test_bsdf_consistency.cpp.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "femto/color.h"
#include "femto/properties.h"

namespace femto {

/// Result of fresnel_dielectric().
struct FresnelDielectric {
    float r;       ///< unpolarised reflectance (the transmittance is 1 - r)
    float cos_t;   ///< signed cosine of the refracted direction, on the side opposite to the
                   ///< incident one; 0 under total internal reflection
    float eta_it;  ///< n_t / n_i of the crossing: eta from outside, 1 / eta from inside
    float eta_ti;  ///< n_i / n_t = 1 / eta_it
};

/// Unpolarised Fresnel reflectance of a smooth dielectric interface of relative index
/// eta = n_int / n_ext, as Mitsuba's fresnel(). `cos_i` is signed: negative means arriving
/// from the inside. r = 0 when eta = 1 (index matched) and r = 1 at grazing incidence and under
/// total internal reflection. The refracted direction of wi is
/// (-wi.x * eta_ti, -wi.y * eta_ti, cos_t).
FresnelDielectric fresnel_dielectric(float cos_i, float eta);

/// Unpolarised Fresnel reflectance of a conductor of relative complex index eta + i k (both
/// divided by the exterior's index) for the incidence cosine `cos_i`, clamped to [0, 1]: the
/// closed form of Moeller ("Optics", 1988) as Mitsuba evaluates it. k = 0 gives a dielectric
/// seen from outside; eta = k = 0 a perfect reflector.
float fresnel_conductor(float cos_i, float eta, float k);
/// fresnel_conductor() per RGB channel.
Color fresnel_conductor(float cos_i, const Color& eta, const Color& k);

/// Index of refraction of a named dielectric, case-insensitive: Mitsuba's table (Hecht,
/// "Optics"; ~589 nm, 0-20 C: "vacuum", "air", "water", "bk7", "diamond", ...) and the femto
/// aliases "acrylic" (1.49) and "glass" (bk7, 1.5046). Nothing for an unknown name.
std::optional<float> lookup_ior(std::string_view name);
/// The names lookup_ior() accepts, lower case, in table order, as "vacuum, helium, ...".
std::string ior_names();

/// Complex index of refraction eta + i k per linear-RGB channel.
struct ComplexIor {
    Color eta, k;
};

/// Complex index of refraction (relative to vacuum) of one of Mitsuba's 37 conductor presets,
/// by its case-sensitive name ("Au", "Ag", "Al", "Cu", "Cr", "W", "a-C", "Na_palik", ...).
/// The values are the measured spectra Mitsuba and PBRT ship (Palik et al. via Luxpop / CXRO /
/// LLNL) integrated against the CIE matching functions into linear sRGB, with the small
/// negative values that projection gives a few transparent materials clamped to zero. Nothing
/// for an unknown name; "none" (Mitsuba's ideal mirror) is not a preset.
std::optional<ComplexIor> lookup_conductor_preset(std::string_view name);
/// The names lookup_conductor_preset() accepts, in table order, as "a-C, Ag, Al, ...".
std::string conductor_preset_names();

/// Reads an index of refraction given as a positive number (at most 1e4) or a name known to
/// lookup_ior() (case-insensitive); `def` (a number or a name, as the schema documents it) when
/// absent. Bad values are located SceneErrors.
float read_ior(const Properties& props, const std::string& name, const std::string& def);

/// Relative complex index of refraction of a conductor (eta + i k, already divided by the
/// exterior index). `perfect` = an ideal mirror (Fresnel term 1).
struct ConductorIor {
    Color eta, k;
    bool perfect = false;

    Color fresnel(float cos_i) const {
        return perfect ? Color(1.f) : fresnel_conductor(cos_i, eta, k);
    }
};

/// Reads `material`, `eta`, `k` and `ext_eta` as Mitsuba 3 does: material "none" (the default)
/// with neither eta nor k is a perfect mirror; eta/k (defaults 0 and 1) may be given instead
/// of a preset, but not together with one.
ConductorIor read_conductor_ior(const Properties& props);

}  // namespace femto
