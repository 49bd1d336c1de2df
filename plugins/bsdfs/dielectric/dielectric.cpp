// dielectric: a smooth interface between two dielectrics, e.g. glass in air (Mitsuba's
// `dielectric`).
//
// Reflection and refraction are both delta lobes. sample() picks reflection with probability
// R (the unpolarised Fresnel reflectance) and refraction with probability 1 - R, so the weight
// of either is the specular_reflectance / specular_transmittance factor alone; under total
// internal reflection R = 1. sample.eta reports n_t / n_i of the crossing (1 for reflection).
// Both sides scatter: wi.z < 0 means the path arrives from inside (int_ior).
//
// Radiance convention: femto traces paths from the camera and carries importance-weighted
// radiance; the 1 / eta^2 factor by which radiance changes when it crosses an interface
// (the non-symmetric part of the refraction BSDF) is deliberately NOT applied. It cancels on
// any path that leaves the medium it entered, which is every path from a camera in air to an
// emitter in air; it would only matter for sensors or emitters inside a dielectric. This
// keeps refraction energy-conserving in the white-furnace sense (R + T = 1). (Mitsuba
// multiplies the refracted weight by eta_ti^2 in Radiance mode.)
#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <string>

#include "femto/bsdf.h"
#include "femto/plugin.h"
#include "femto/texture.h"

namespace {

using namespace femto;

// ---- Named dielectric IORs and the dielectric Fresnel term. --------------------------------
// The same block is in dielectric.cpp and plastic.cpp (plugins may not share source files);
// it belongs in a host header (femto/fresnel.h) once there is one.

struct IorEntry {
    const char* name;
    float value;
};
/// Mitsuba's table of dielectric indices of refraction (Hecht, Optics; ~589 nm, 0-20 C).
constexpr IorEntry kIorTable[] = {
    {"vacuum", 1.0f},
    {"helium", 1.000036f},
    {"hydrogen", 1.000132f},
    {"air", 1.000277f},
    {"carbon dioxide", 1.00045f},
    {"water", 1.3330f},
    {"acetone", 1.36f},
    {"ethanol", 1.361f},
    {"carbon tetrachloride", 1.461f},
    {"glycerol", 1.4729f},
    {"benzene", 1.501f},
    {"silicone oil", 1.52045f},
    {"bromine", 1.661f},
    {"water ice", 1.31f},
    {"fused quartz", 1.458f},
    {"pyrex", 1.470f},
    {"acrylic glass", 1.49f},
    {"polypropylene", 1.49f},
    {"bk7", 1.5046f},
    {"sodium chloride", 1.544f},
    {"amber", 1.55f},
    {"pet", 1.5750f},
    {"diamond", 2.419f},
    // femto aliases (not in Mitsuba's table)
    {"acrylic", 1.49f},
    {"glass", 1.5046f},
};

std::string to_lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

/// Reads an index of refraction given as a positive number or a name from kIorTable
/// (case-insensitive); `def` when absent.
float read_ior(const Properties& props, const std::string& name, float def) {
    if (!props.has(name)) return def;
    if (props.type(name) == Properties::Type::String) {
        const std::string value = to_lower(props.get_string(name));
        for (const IorEntry& e : kIorTable)
            if (value == e.name) return e.value;
        std::string valid;
        for (const IorEntry& e : kIorTable)
            valid += std::string(valid.empty() ? "" : ", ") + e.name;
        props.fail(name, "unknown index of refraction \"" + value + "\" for \"" + name +
                             "\"; give a number or one of: " + valid);
    }
    const double v = props.get_float(name);
    if (!(v > 0.0)) props.fail(name, "\"" + name + "\" must be a positive index of refraction");
    return static_cast<float>(v);
}

/// Unpolarised Fresnel reflectance of a dielectric interface with relative IOR eta = n_int /
/// n_ext, as Mitsuba's fresnel(): `cos_i` is signed (negative = arriving from the inside).
/// Also returns the signed cosine of the refracted direction (on the opposite side; 0 under
/// total internal reflection) and the relative IORs eta_it = n_t / n_i and eta_ti = n_i / n_t.
struct FresnelDielectric {
    float r, cos_t, eta_it, eta_ti;
};
FresnelDielectric fresnel_dielectric(float cos_i, float eta) {
    const bool outside = cos_i >= 0.f;
    const float eta_it = outside ? eta : 1.f / eta, eta_ti = outside ? 1.f / eta : eta;
    const float cos_t2 = 1.f - eta_ti * eta_ti * (1.f - cos_i * cos_i);
    const float ci = std::abs(cos_i), ct = safe_sqrt(cos_t2);
    float r;
    if (eta == 1.f)
        r = 0.f;  // index matched
    else if (ci == 0.f || cos_t2 <= 0.f)
        r = 1.f;  // grazing, or total internal reflection
    else {
        const float a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
        const float a_p = (ct - eta_it * ci) / (ct + eta_it * ci);
        r = 0.5f * (a_s * a_s + a_p * a_p);
    }
    return {r, outside ? -ct : ct, eta_it, eta_ti};
}
// ---- end of the shared block ---------------------------------------------------------------

class Dielectric final : public Bsdf {
public:
    explicit Dielectric(const Properties& props)
        : specular_reflectance_(get_texture(props, "specular_reflectance", Color(1.f))),
          specular_transmittance_(get_texture(props, "specular_transmittance", Color(1.f))) {
        const float int_ior = read_ior(props, "int_ior", 1.5046f);    // bk7
        const float ext_ior = read_ior(props, "ext_ior", 1.000277f);  // air
        eta_ = int_ior / ext_ior;
    }

    uint32_t flags() const override { return kBsdfDeltaReflection | kBsdfDeltaTransmission; }

    BsdfSample sample(const Hit& hit, const Vec3& wi, float u_lobe, Vec2) const override {
        BsdfSample s;
        const FresnelDielectric f = fresnel_dielectric(wi.z, eta_);
        if (u_lobe < f.r) {
            s.wo = Vec3(-wi.x, -wi.y, wi.z);
            s.pdf = f.r;
            s.eta = 1.f;
            s.sampled_lobe = kBsdfDeltaReflection;
            s.weight = specular_reflectance_->eval(hit);
        } else {
            // Snell: the tangential part scales by eta_ti and flips, the normal part is cos_t.
            s.wo = Vec3(-wi.x * f.eta_ti, -wi.y * f.eta_ti, f.cos_t);
            s.pdf = 1.f - f.r;
            s.eta = f.eta_it;
            s.sampled_lobe = kBsdfDeltaTransmission;
            s.weight = specular_transmittance_->eval(hit);  // no 1/eta^2: see the top comment
        }
        return s;
    }

    Color eval(const Hit&, const Vec3&, const Vec3&) const override { return Color(0.f); }
    float pdf(const Hit&, const Vec3&, const Vec3&) const override { return 0.f; }

private:
    float eta_ = 1.f;  ///< int_ior / ext_ior
    std::shared_ptr<Texture> specular_reflectance_, specular_transmittance_;
};

}  // namespace

FEMTO_PLUGIN(
    Dielectric, femto::PluginKind::Bsdf, "dielectric",
    "Smooth dielectric interface (glass, water): Fresnel-weighted reflection and "
    "refraction",
    {{"int_ior", "float|string", "bk7",
      "interior index of refraction (number or name: water, bk7, diamond, ...)"},
     {"ext_ior", "float|string", "air", "exterior index of refraction (number or name)"},
     {"specular_reflectance", "color|texture", "1", "factor on the reflection (physically 1)"},
     {"specular_transmittance", "color|texture", "1", "factor on the transmission (physically 1)"}})
