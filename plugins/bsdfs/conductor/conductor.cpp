// conductor: a perfectly smooth metal mirror (Mitsuba's `conductor`).
//
// A delta reflection weighted by the exact unpolarised Fresnel reflectance of a conductor with
// complex index of refraction eta + i k (per RGB channel), relative to an exterior dielectric
// of index ext_eta. One-sided like Mitsuba's: nothing is reflected when wi.z <= 0 (use
// `twosided`). eval() and pdf() are zero: a delta lobe is only reachable through sample().
//
// Differences from Mitsuba: presets are RGB triples (femto renders in linear RGB); `ext_eta`
// (Mitsuba 0.6's extEta, absent in Mitsuba 3) defaults to 1 like Mitsuba 3's behaviour, where
// Mitsuba 0.6 used air (1.000277, a 0.03% change of the reflectance). The default material is
// Mitsuba 3's "none" (Mitsuba 0.6 defaulted to Cu).
#include <memory>
#include <optional>
#include <string>

#include "femto/bsdf.h"
#include "femto/fresnel.h"
#include "femto/plugin.h"
#include "femto/texture.h"

namespace {

using namespace femto;

/// Reads an index of refraction given as a positive number or a name known to lookup_ior()
/// (case-insensitive); `def` when absent.
float read_ior(const Properties& props, const std::string& name, float def) {
    if (!props.has(name)) return def;
    if (props.type(name) == Properties::Type::String) {
        const std::string value = props.get_string(name);
        if (const std::optional<float> ior = lookup_ior(value)) return *ior;
        props.fail(name, "unknown index of refraction \"" + value + "\" for \"" + name +
                             "\"; give a number or one of: " + ior_names());
    }
    const double v = props.get_float(name);
    if (!(v > 0.0)) props.fail(name, "\"" + name + "\" must be a positive index of refraction");
    return static_cast<float>(v);
}

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
ConductorIor read_conductor_ior(const Properties& props) {
    const std::string material = props.get_string("material", "none");
    const float ext_eta = read_ior(props, "ext_eta", 1.f);
    ConductorIor ior;
    if (material == "none") {
        ior.perfect = !props.has("eta") && !props.has("k");
        const Color eta = props.get_color("eta", Color(0.f));
        const Color k = props.get_color("k", Color(1.f));
        for (int i = 0; i < 3; ++i) {
            if (!(eta[i] >= 0.f)) props.fail("eta", "\"eta\" must be non-negative");
            if (!(k[i] >= 0.f)) props.fail("k", "\"k\" must be non-negative");
        }
        ior.eta = eta / ext_eta;
        ior.k = k / ext_eta;
        return ior;
    }
    if (props.has("eta") || props.has("k"))
        props.fail(props.has("eta") ? "eta" : "k",
                   "give either a conductor \"material\" preset or \"eta\"/\"k\", not both");
    const std::optional<ComplexIor> preset = lookup_conductor_preset(material);
    if (!preset)
        props.fail("material", "unknown conductor material \"" + material +
                                   "\"; valid presets: none, " + conductor_preset_names());
    ior.eta = preset->eta / ext_eta;
    ior.k = preset->k / ext_eta;
    return ior;
}

class Conductor final : public Bsdf {
public:
    explicit Conductor(const Properties& props)
        : ior_(read_conductor_ior(props)),
          specular_reflectance_(get_texture(props, "specular_reflectance", Color(1.f))) {}

    uint32_t flags() const override { return kBsdfDeltaReflection; }

    BsdfSample sample(const Hit& hit, const Vec3& wi, float, Vec2) const override {
        BsdfSample s;
        if (wi.z <= 0.f) return s;
        s.wo = Vec3(-wi.x, -wi.y, wi.z);
        s.pdf = 1.f;
        s.eta = 1.f;
        s.sampled_lobe = kBsdfDeltaReflection;
        s.weight = specular_reflectance_->eval(hit) * ior_.fresnel(wi.z);
        return s;
    }

    Color eval(const Hit&, const Vec3&, const Vec3&) const override { return Color(0.f); }
    float pdf(const Hit&, const Vec3&, const Vec3&) const override { return 0.f; }

private:
    ConductorIor ior_;
    std::shared_ptr<Texture> specular_reflectance_;
};

}  // namespace

FEMTO_PLUGIN(Conductor, femto::PluginKind::Bsdf, "conductor",
             "Smooth conductor (metal mirror) with exact complex Fresnel reflectance",
             {{"material", "string", "none",
               "conductor preset (Au, Ag, Al, Cu, Cr, W, ...; \"none\" = ideal mirror)"},
              {"eta", "color", "0", "real part of the complex IOR (instead of a preset)"},
              {"k", "color", "1", "imaginary part (absorption) of the complex IOR"},
              {"ext_eta", "float|string", "1", "IOR of the exterior dielectric (number or name)"},
              {"specular_reflectance", "color|texture", "1",
               "factor on the reflection (physically 1)"}})
