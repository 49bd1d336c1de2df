#include "femto/fresnel.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include "femto/math.h"

namespace femto {

namespace {

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

struct ConductorPreset {
    const char* name;
    Color eta, k;
};
/// Complex IORs of Mitsuba's conductor presets as linear-sRGB triples: the measured spectra
/// Mitsuba and PBRT ship (Palik et al. via Luxpop / CXRO / LLNL) integrated against the CIE
/// matching functions (the table Tungsten derived from the same data). Small negative values
/// that the spectral-to-RGB projection produced for a few transparent materials are clamped
/// to zero when the table is read.
constexpr ConductorPreset kConductorPresets[] = {
    {"a-C",
     {2.9440999183f, 2.2271502925f, 1.9681668794f},
     {0.8874329109f, 0.7993216383f, 0.8152862927f}},
    {"Ag",
     {0.1552646489f, 0.1167232965f, 0.1383806959f},
     {4.8283433224f, 3.1222459278f, 2.1469504455f}},
    {"Al",
     {1.6574599595f, 0.8803689579f, 0.5212287346f},
     {9.2238691996f, 6.2695232477f, 4.8370012281f}},
    {"AlAs",
     {3.6051023902f, 3.2329365777f, 2.2175611545f},
     {0.0006670247f, -0.0004999400f, 0.0074261204f}},
    {"AlSb",
     {-0.0485225705f, 4.1427547893f, 4.6697691348f},
     {-0.0363741915f, 0.0937665154f, 1.3007390124f}},
    {"Au",
     {0.1431189557f, 0.3749570432f, 1.4424785571f},
     {3.9831604247f, 2.3857207478f, 1.6032152899f}},
    {"Be",
     {4.1850592788f, 3.1850604423f, 2.7840913457f},
     {3.8354398268f, 3.0101260162f, 2.8690088743f}},
    {"Cr",
     {4.3696828663f, 2.9167024892f, 1.6547005413f},
     {5.2064337956f, 4.2313645277f, 3.7549467933f}},
    {"CsI", {2.1449030413f, 1.7023164587f, 1.6624194173f}, {0.0f, 0.0f, 0.0f}},
    {"Cu",
     {0.2004376970f, 0.9240334304f, 1.1022119527f},
     {3.9129485033f, 2.4528477015f, 2.1421879552f}},
    {"Cu2O",
     {3.5492833755f, 2.9520622449f, 2.7369202137f},
     {0.1132179294f, 0.1946659670f, 0.6001681264f}},
    {"CuO",
     {3.2453822204f, 2.4496293965f, 2.1974114493f},
     {0.5202739621f, 0.5707372756f, 0.7172250613f}},
    {"d-C", {2.7112524747f, 2.3185812849f, 2.2288565009f}, {0.0f, 0.0f, 0.0f}},
    {"Hg",
     {2.3989314904f, 1.4400254917f, 0.9095512090f},
     {6.3276269444f, 4.3719414152f, 3.4217899270f}},
    {"HgTe",
     {4.7795267752f, 3.2309984581f, 2.6600252401f},
     {1.6319827058f, 1.5808189339f, 1.7295753852f}},
    {"Ir",
     {3.0864098394f, 2.0821938440f, 1.6178866805f},
     {5.5921510077f, 4.0671757150f, 3.2672611269f}},
    {"K",
     {0.0640493070f, 0.0464100621f, 0.0381842017f},
     {2.1042155920f, 1.3489364357f, 0.9132113889f}},
    {"Li",
     {0.2657871942f, 0.1956102432f, 0.2209198538f},
     {3.5401743407f, 2.3111306542f, 1.6685930000f}},
    {"MgO", {2.0895885542f, 1.6507224525f, 1.5948759692f}, {0.0f, 0.0f, 0.0f}},
    {"Mo",
     {4.4837010280f, 3.5254578255f, 2.7760769438f},
     {4.1111307988f, 3.4208716252f, 3.1506031404f}},
    {"Na_palik",
     {0.0602665320f, 0.0561412435f, 0.0619909494f},
     {3.1792906496f, 2.1124800781f, 1.5790940266f}},
    {"Nb",
     {3.4201353595f, 2.7901921379f, 2.3955856658f},
     {3.4413817900f, 2.7376437930f, 2.5799132708f}},
    {"Ni_palik",
     {2.3672753521f, 1.6633583302f, 1.4670554172f},
     {4.4988329911f, 3.0501643957f, 2.3454274399f}},
    {"Rh",
     {2.5857954933f, 1.8601866068f, 1.5544279524f},
     {6.7822927110f, 4.7029501026f, 3.9760892461f}},
    {"Se",
     {4.0592611085f, 2.8426947380f, 2.8207582835f},
     {0.7543791750f, 0.6385150558f, 0.5215872029f}},
    {"SiC",
     {3.1723450205f, 2.5259677964f, 2.4793623897f},
     {0.0000007284f, -0.0000006859f, 0.0000100150f}},
    {"SnTe", {4.5251865890f, 1.9811525984f, 1.2816819226f}, {0.0f, 0.0f, 0.0f}},
    {"Ta",
     {2.0625846607f, 2.3930915569f, 2.6280684948f},
     {2.4080467973f, 1.7413705864f, 1.9470377016f}},
    {"Te",
     {7.3908396088f, 4.4821028985f, 2.6370708478f},
     {3.2561412892f, 3.5273908133f, 3.2921683116f}},
    {"ThF4", {1.8307187117f, 1.4422274283f, 1.3876488528f}, {0.0f, 0.0f, 0.0f}},
    {"TiC",
     {3.7004673762f, 2.8374356509f, 2.5823030278f},
     {3.2656905818f, 2.3515586388f, 2.1727857800f}},
    {"TiN",
     {1.6484691607f, 1.1504482522f, 1.3797795097f},
     {3.3684596226f, 1.9434888540f, 1.1020123347f}},
    {"TiO2",
     {3.4566203131f, 2.8017076558f, 2.9051485020f},
     {0.0001026662f, -0.0000897534f, 0.0006356902f}},
    {"VC",
     {3.6575665991f, 2.7527298065f, 2.5326814570f},
     {3.0683516659f, 2.1986687713f, 1.9631816252f}},
    {"VN",
     {2.8656011588f, 2.1191817791f, 1.9400767149f},
     {3.0323264950f, 2.0561075580f, 1.6162930914f}},
    {"V_palik",
     {4.2775126218f, 3.5131538236f, 2.7611257461f},
     {3.4911844504f, 2.8893580874f, 3.1116965117f}},
    {"W",
     {4.3707029924f, 3.3002972445f, 2.9982666528f},
     {3.5006778591f, 2.6048652781f, 2.2731930614f}},
};

Color clamp_non_negative(const Color& c) {
    return {std::max(c.r, 0.f), std::max(c.g, 0.f), std::max(c.b, 0.f)};
}

}  // namespace

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

float fresnel_conductor(float cos_i, float eta, float k) {
    cos_i = clamp(cos_i, 0.f, 1.f);
    const float cos2 = cos_i * cos_i, sin2 = 1.f - cos2, sin4 = sin2 * sin2;
    const float temp1 = eta * eta - k * k - sin2;
    const float a2pb2 = safe_sqrt(temp1 * temp1 + 4.f * k * k * eta * eta);
    const float a = safe_sqrt(0.5f * (a2pb2 + temp1));
    const float term1 = a2pb2 + cos2, term2 = 2.f * cos_i * a;
    // The denominators vanish only for eta = k = 0 (at grazing / normal incidence): a
    // perfect reflector in the limit.
    const float rs = term1 + term2 > 0.f ? (term1 - term2) / (term1 + term2) : 1.f;
    const float term3 = a2pb2 * cos2 + sin4, term4 = term2 * sin2;
    const float rp = term3 + term4 > 0.f ? rs * (term3 - term4) / (term3 + term4) : rs;
    return 0.5f * (rs + rp);
}

Color fresnel_conductor(float cos_i, const Color& eta, const Color& k) {
    return {fresnel_conductor(cos_i, eta.r, k.r), fresnel_conductor(cos_i, eta.g, k.g),
            fresnel_conductor(cos_i, eta.b, k.b)};
}

std::optional<float> lookup_ior(std::string_view name) {
    std::string lower(name);
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    for (const IorEntry& e : kIorTable)
        if (lower == e.name) return e.value;
    return std::nullopt;
}

std::string ior_names() {
    std::string names;
    for (const IorEntry& e : kIorTable) names += std::string(names.empty() ? "" : ", ") + e.name;
    return names;
}

std::optional<ComplexIor> lookup_conductor_preset(std::string_view name) {
    for (const ConductorPreset& p : kConductorPresets)
        if (name == p.name) return ComplexIor{clamp_non_negative(p.eta), clamp_non_negative(p.k)};
    return std::nullopt;
}

std::string conductor_preset_names() {
    std::string names;
    for (const ConductorPreset& p : kConductorPresets)
        names += std::string(names.empty() ? "" : ", ") + p.name;
    return names;
}

/// Indices of refraction (and conductors' eta and k) above this are refused: far beyond any
/// material's (a few, or tens for metals' k), and the Fresnel terms overflow to NaN near 1e19.
constexpr double kMaxIor = 1e4;

/// Reads an index of refraction given as a positive number or a name known to lookup_ior()
/// (case-insensitive); `def` (a number or a name) when absent.
float read_ior(const Properties& props, const std::string& name, const std::string& def) {
    if (!props.has(name)) {
        props.note_default(name, def);
        if (const std::optional<float> ior = lookup_ior(def)) return *ior;
        return std::stof(def);
    }
    if (props.type(name) == Properties::Type::String) {
        const std::string value = props.get_string(name);
        if (const std::optional<float> ior = lookup_ior(value)) return *ior;
        props.fail(name, "unknown index of refraction \"" + value + "\" for \"" + name +
                             "\"; give a number or one of: " + ior_names());
    }
    const double v = props.get_float(name);
    if (!(v > 0.0 && v <= kMaxIor))
        props.fail(name, fmt::format("\"{}\" must be a positive index of refraction of at most {}, "
                                     "got {}",
                                     name, kMaxIor, v));
    return static_cast<float>(v);
}

/// Reads `material`, `eta`, `k` and `ext_eta` as Mitsuba 3 does: material "none" (the default)
/// with neither eta nor k is a perfect mirror; eta/k (defaults 0 and 1) may be given instead
/// of a preset, but not together with one.
ConductorIor read_conductor_ior(const Properties& props) {
    const std::string material = props.get_string("material", "none");
    const float ext_eta = read_ior(props, "ext_eta", "1");
    ConductorIor ior;
    if (material == "none") {
        ior.perfect = !props.has("eta") && !props.has("k");
        const Color eta = props.get_color("eta", Color(0.f));
        const Color k = props.get_color("k", Color(1.f));
        for (int i = 0; i < 3; ++i) {
            if (!(eta[i] >= 0.f && eta[i] <= kMaxIor))
                props.fail("eta", fmt::format("\"eta\" must be from 0 to {}", kMaxIor));
            if (!(k[i] >= 0.f && k[i] <= kMaxIor))
                props.fail("k", fmt::format("\"k\" must be from 0 to {}", kMaxIor));
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

}  // namespace femto
