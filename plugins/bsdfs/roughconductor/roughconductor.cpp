// roughconductor: a rough metal described by a microfacet model (Mitsuba's `roughconductor`).
//
// f(wi, wo) = F(wi.h) D(h) G(wi, wo, h) / (4 cos_i cos_o) with h the half vector, Beckmann or
// GGX normal distributions (isotropic or anisotropic), Smith's separable uncorrelated
// shadowing-masking G = G1(wi) G1(wo) and the exact conductor Fresnel term per RGB channel.
// One-sided like Mitsuba's (zero unless wi.z > 0 and wo.z > 0).
//
// Sampling (as Mitsuba): with sample_visible = true the distribution of visible normals
// D_wi(m) = G1(wi, m) max(0, wi.m) D(m) / cos_i is sampled exactly: GGX by Heitz's 2018
// method, Beckmann by Heitz & d'Eon 2014 (stretch, sample the alpha = 1 slope distribution by
// a safeguarded Newton inversion of its CDF in the erf domain, rotate, unstretch). With
// sample_visible = false, D(m) cos(theta_m) is sampled. The reflected direction's pdf is
// p(m) / (4 wo.m).
//
// Difference from Mitsuba: the Beckmann G1 is the exact Smith term 1 / (1 + Lambda(a)) with
// Lambda(a) = (exp(-a^2) / (a sqrt(pi)) - erfc(a)) / 2 and a = 1 / (alpha tan(theta)), where
// Mitsuba uses a rational fit (< 0.35% error). The exact term makes the visible-normal pdf
// integrate to exactly one, which the chi-square tests rely on. Roughness values below 1e-4
// are clamped to 1e-4 (as Mitsuba does). Roughness is a float, not a texture.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "femto/bsdf.h"
#include "femto/plugin.h"
#include "femto/texture.h"

namespace {

using namespace femto;

// ---- Conductor presets, named dielectric IORs and the conductor Fresnel term. -------------
// The same block is in conductor.cpp and roughconductor.cpp (plugins may not share source
// files); it belongs in a host header (femto/fresnel.h) once there is one.

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

struct ConductorPreset {
    const char* name;
    Color eta, k;
};
/// Complex IORs of Mitsuba's conductor presets as linear-sRGB triples: the measured spectra
/// Mitsuba and PBRT ship (Palik et al. via Luxpop / CXRO / LLNL) integrated against the CIE
/// matching functions (the table Tungsten derived from the same data). Small negative values
/// that the spectral-to-RGB projection produced for a few transparent materials are clamped
/// to zero when the table is read.
const ConductorPreset kConductorPresets[] = {
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

/// Relative complex index of refraction of a conductor (eta + i k, already divided by the
/// exterior index). `perfect` = an ideal mirror (Fresnel term 1).
struct ConductorIor {
    Color eta, k;
    bool perfect = false;
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
    for (const ConductorPreset& p : kConductorPresets)
        if (material == p.name) {
            ior.eta = clamp_non_negative(p.eta) / ext_eta;
            ior.k = clamp_non_negative(p.k) / ext_eta;
            return ior;
        }
    std::string valid = "none";
    for (const ConductorPreset& p : kConductorPresets) valid += std::string(", ") + p.name;
    props.fail("material",
               "unknown conductor material \"" + material + "\"; valid presets: " + valid);
}

/// Unpolarised Fresnel reflectance of a conductor with relative complex IOR eta + i k, for
/// incidence cosine `cos_i` (clamped to [0, 1]). The closed form of Moeller ("Optics", 1988)
/// as Mitsuba evaluates it; tests compare it with the textbook complex-amplitude form.
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

Color fresnel_conductor(float cos_i, const ConductorIor& ior) {
    if (ior.perfect) return Color(1.f);
    return {fresnel_conductor(cos_i, ior.eta.r, ior.k.r),
            fresnel_conductor(cos_i, ior.eta.g, ior.k.g),
            fresnel_conductor(cos_i, ior.eta.b, ior.k.b)};
}
// ---- end of the shared block ---------------------------------------------------------------

constexpr double kPiD = 3.14159265358979323846;
constexpr double kInvSqrtPiD = 0.56418958354775628695;

/// Inverse error function in double precision: Giles' (2010) approximation refined by Newton
/// steps (on erfc in the tails, where erf itself has no relative precision left).
double erfinv(double y) {
    if (y <= -1.0) return -std::numeric_limits<double>::infinity();
    if (y >= 1.0) return std::numeric_limits<double>::infinity();
    double w = -std::log((1.0 - y) * (1.0 + y)), p;
    if (w < 5.0) {
        w -= 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        w = std::sqrt(w) - 3.0;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    const double ay = std::abs(y);
    double x = std::abs(p * y);
    for (int i = 0; i < 3; ++i) {
        const double deriv = 2.0 * kInvSqrtPiD * std::exp(-x * x);
        if (!(deriv > 0.0)) break;
        // erf(x) - |y|, computed as (1 - |y|) - erfc(x) in the upper half.
        const double err = ay > 0.5 ? (1.0 - ay) - std::erfc(x) : std::erf(x) - ay;
        const double next = x - err / deriv;
        if (!std::isfinite(next) || next < 0.0) break;
        x = next;
    }
    return std::copysign(x, y);
}

/// A float from [0, 1) moved into the open interval (0, 1) (the midpoint of its 2^-24 cell),
/// so that logarithms and erfinv of it stay finite.
double open_unit(float u) {
    return std::clamp(static_cast<double>(u), 0.0, 1.0 - 0x1p-24) + 0x1p-25;
}

enum class MicrofacetType { Beckmann, GGX };

class Microfacet {
public:
    Microfacet(MicrofacetType type, float alpha_u, float alpha_v, bool sample_visible)
        : type_(type), au_(alpha_u), av_(alpha_v), visible_(sample_visible) {}

    bool sample_visible() const { return visible_; }

    /// Normal distribution D(m) (projected area normalised: integral of D(m) m.z = 1).
    float D(const Vec3& m) const {
        if (m.z <= 0.f) return 0.f;
        const float cos2 = m.z * m.z;
        const float ex = m.x / au_, ey = m.y / av_;
        float r;
        if (type_ == MicrofacetType::Beckmann) {
            r = std::exp(-(ex * ex + ey * ey) / cos2) / (kPi * au_ * av_ * cos2 * cos2);
        } else {
            const float t = ex * ex + ey * ey + cos2;
            r = 1.f / (kPi * au_ * av_ * t * t);
        }
        return r * m.z > 1e-20f ? r : 0.f;
    }

    /// Smith's monodirectional shadowing-masking term for direction v and microfacet m.
    float G1(const Vec3& v, const Vec3& m) const {
        if (dot(v, m) * v.z <= 0.f) return 0.f;
        const float xy = (au_ * v.x) * (au_ * v.x) + (av_ * v.y) * (av_ * v.y);
        if (xy == 0.f) return 1.f;
        const float tan2 = xy / (v.z * v.z);  // alpha-projected tan^2(theta_v)
        if (type_ == MicrofacetType::Beckmann) {
            const double a = 1.0 / std::sqrt(static_cast<double>(tan2));
            const double lambda = 0.5 * (std::exp(-a * a) * kInvSqrtPiD / a - std::erfc(a));
            return static_cast<float>(1.0 / (1.0 + std::max(lambda, 0.0)));
        }
        return 2.f / (1.f + std::sqrt(1.f + tan2));
    }

    /// Density of sample() returning microfacet normal m for incident direction wi.
    float pdf(const Vec3& wi, const Vec3& m) const {
        if (visible_) return D(m) * G1(wi, m) * std::max(0.f, dot(wi, m)) / wi.z;
        return D(m) * m.z;
    }

    /// Samples a microfacet normal (wi.z > 0). Returns false when sampling failed.
    bool sample(const Vec3& wi, Vec2 u, Vec3& m) const {
        if (visible_) {
            m = type_ == MicrofacetType::GGX ? sample_visible_ggx(wi, u)
                                             : sample_visible_beckmann(wi, u);
        } else {
            m = sample_full(u);
        }
        return is_finite(m) && m.z > 0.f;
    }

private:
    /// Heitz 2018, "Sampling the GGX Distribution of Visible Normals".
    Vec3 sample_visible_ggx(const Vec3& wi, Vec2 u) const {
        const Vec3 vh = normalize(Vec3(au_ * wi.x, av_ * wi.y, wi.z));
        const float lensq = vh.x * vh.x + vh.y * vh.y;
        const Vec3 t1 = lensq > 0.f ? Vec3(-vh.y, vh.x, 0.f) / std::sqrt(lensq) : Vec3(1, 0, 0);
        const Vec3 t2 = cross(vh, t1);
        const float r = std::sqrt(u.x), phi = 2.f * kPi * u.y;
        const float p1 = r * std::cos(phi);
        float p2 = r * std::sin(phi);
        const float s = 0.5f * (1.f + vh.z);
        p2 = (1.f - s) * safe_sqrt(1.f - p1 * p1) + s * p2;
        const Vec3 nh = t1 * p1 + t2 * p2 + vh * safe_sqrt(1.f - p1 * p1 - p2 * p2);
        return normalize(Vec3(au_ * nh.x, av_ * nh.y, std::max(0.f, nh.z)));
    }

    /// Heitz & d'Eon 2014 for Beckmann: stretch wi to the alpha = 1 configuration, sample
    /// the visible slopes there, rotate back to wi's azimuth and unstretch.
    Vec3 sample_visible_beckmann(const Vec3& wi, Vec2 u) const {
        const double sx = static_cast<double>(au_) * wi.x, sy = static_cast<double>(av_) * wi.y;
        const double sz = wi.z;
        const double sin_t = std::sqrt(sx * sx + sy * sy);
        double cos_phi = 1.0, sin_phi = 0.0;
        if (sin_t > 0.0) {
            cos_phi = sx / sin_t;
            sin_phi = sy / sin_t;
        }
        double slope_x, slope_y;
        sample_visible_11_beckmann(sin_t, sz, u, slope_x, slope_y);
        const double rx = (cos_phi * slope_x - sin_phi * slope_y) * au_;
        const double ry = (sin_phi * slope_x + cos_phi * slope_y) * av_;
        const double inv = 1.0 / std::sqrt(rx * rx + ry * ry + 1.0);
        return {static_cast<float>(-rx * inv), static_cast<float>(-ry * inv),
                static_cast<float>(inv)};
    }

    /// Visible slopes of the alpha = 1 Beckmann surface seen from (sin_t, 0, cos_t) (not
    /// necessarily normalised). The x slope has the CDF
    ///   C(b) = (1 + b + tan_t / sqrt(pi) exp(-erfinv(b)^2)) / (1 + c + tan_t / sqrt(pi)
    ///   exp(-cot_t^2))
    /// over b = erf(slope) in [-1, c = erf(cot_t)], inverted by Newton steps that fall back to
    /// bisection whenever a step leaves the bracket; the y slope is a unit Gaussian.
    static void sample_visible_11_beckmann(double sin_t, double cos_t, Vec2 u, double& slope_x,
                                           double& slope_y) {
        const double u1 = open_unit(u.x), u2 = open_unit(u.y);
        if (sin_t < 1e-7 * cos_t) {  // normal incidence: the full slope distribution
            const double r = std::sqrt(-std::log(u1)), phi = 2.0 * kPiD * u2;
            slope_x = r * std::cos(phi);
            slope_y = r * std::sin(phi);
            return;
        }
        const double tan_t = sin_t / cos_t, cot_t = cos_t / sin_t;
        double a = -1.0, c = std::erf(cot_t);
        const double norm = 1.0 / (1.0 + c + kInvSqrtPiD * tan_t * std::exp(-cot_t * cot_t));
        // Initial guess: the exact inverse for grazing incidence (Mitsuba 3).
        double b = c - (c + 1.0) * std::erf(std::sqrt(-std::log(u1)));
        for (int it = 0; it < 100; ++it) {
            const double x = erfinv(b);
            const double value = norm * (1.0 + b + kInvSqrtPiD * tan_t * std::exp(-x * x)) - u1;
            if (std::abs(value) < 1e-13) break;
            if (value > 0.0)
                c = b;
            else
                a = b;
            const double deriv = norm * (1.0 - x * tan_t);
            double next = b - value / deriv;
            if (!(deriv > 0.0) || !(next > a && next < c)) next = 0.5 * (a + c);
            if (next == b) break;
            b = next;
        }
        slope_x = erfinv(b);
        slope_y = erfinv(2.0 * u2 - 1.0);
    }

    /// Samples D(m) cos(theta_m) (Walter et al. 2007; anisotropic azimuth as Mitsuba).
    Vec3 sample_full(Vec2 u) const {
        const double ux = std::clamp(static_cast<double>(u.x), 0.0, 1.0 - 0x1p-24);
        double cos_phi, sin_phi, alpha2;
        if (au_ == av_) {
            const double phi = 2.0 * kPiD * u.y;
            cos_phi = std::cos(phi);
            sin_phi = std::sin(phi);
            alpha2 = static_cast<double>(au_) * au_;
        } else {
            const double tmp = (static_cast<double>(av_) / au_) * std::tan(2.0 * kPiD * u.y);
            if (std::isfinite(tmp)) {
                cos_phi =
                    std::copysign(1.0 / std::sqrt(tmp * tmp + 1.0), std::abs(u.y - 0.5) - 0.25);
                sin_phi = cos_phi * tmp;
            } else {
                cos_phi = 0.0;
                sin_phi = u.y < 0.5 ? 1.0 : -1.0;
            }
            alpha2 = 1.0 / ((cos_phi / au_) * (cos_phi / au_) + (sin_phi / av_) * (sin_phi / av_));
        }
        const double tan2 = type_ == MicrofacetType::Beckmann ? -alpha2 * std::log1p(-ux)
                                                              : alpha2 * ux / (1.0 - ux);
        const double cos_t = 1.0 / std::sqrt(1.0 + tan2);
        const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
        return {static_cast<float>(sin_t * cos_phi), static_cast<float>(sin_t * sin_phi),
                static_cast<float>(cos_t)};
    }

    MicrofacetType type_;
    float au_, av_;
    bool visible_;
};

Microfacet read_microfacet(const Properties& props) {
    const std::string dist = to_lower(props.get_string("distribution", "beckmann"));
    MicrofacetType type;
    if (dist == "beckmann")
        type = MicrofacetType::Beckmann;
    else if (dist == "ggx")
        type = MicrofacetType::GGX;
    else
        props.fail("distribution",
                   "unknown microfacet distribution \"" + dist + "\"; valid: beckmann, ggx");
    double au = 0.1, av = 0.1;
    const bool has_u = props.has("alpha_u"), has_v = props.has("alpha_v");
    if (props.has("alpha")) {
        if (has_u || has_v)
            props.fail(has_u ? "alpha_u" : "alpha_v",
                       "give either \"alpha\" or \"alpha_u\"/\"alpha_v\", not both");
        au = av = props.get_float("alpha");
        if (!(au > 0.0)) props.fail("alpha", "\"alpha\" must be positive");
    } else if (has_u || has_v) {
        if (!has_u || !has_v)
            props.fail(has_u ? "alpha_u" : "alpha_v",
                       "an anisotropic roughness needs both \"alpha_u\" and \"alpha_v\"");
        au = props.get_float("alpha_u");
        av = props.get_float("alpha_v");
        if (!(au > 0.0)) props.fail("alpha_u", "\"alpha_u\" must be positive");
        if (!(av > 0.0)) props.fail("alpha_v", "\"alpha_v\" must be positive");
    }
    const bool visible = props.get_bool("sample_visible", true);
    return Microfacet(type, static_cast<float>(std::max(au, 1e-4)),
                      static_cast<float>(std::max(av, 1e-4)), visible);
}

class RoughConductor final : public Bsdf {
public:
    explicit RoughConductor(const Properties& props)
        : distr_(read_microfacet(props)),
          ior_(read_conductor_ior(props)),
          specular_reflectance_(get_texture(props, "specular_reflectance", Color(1.f))) {}

    uint32_t flags() const override { return kBsdfGlossyReflection; }

    BsdfSample sample(const Hit& hit, const Vec3& wi, float, Vec2 u) const override {
        BsdfSample s;
        if (wi.z <= 0.f) return s;
        Vec3 m;
        if (!distr_.sample(wi, u, m)) return s;
        const float wi_m = dot(wi, m);
        if (!(wi_m > 0.f)) return s;
        const Vec3 wo = reflect(wi, m);
        if (!(wo.z > 0.f)) return s;
        const float pdf = distr_.pdf(wi, m) / (4.f * wi_m);  // wo.m == wi.m
        if (!(pdf > 0.f) || !std::isfinite(pdf)) return s;
        float g;
        if (distr_.sample_visible())
            g = distr_.G1(wo, m);  // D G1(wi) G1(wo) / (4 cos_i) over D G1(wi) / (4 cos_i)
        else
            g = distr_.G1(wi, m) * distr_.G1(wo, m) * wi_m / (wi.z * m.z);
        s.wo = wo;
        s.pdf = pdf;
        s.eta = 1.f;
        s.sampled_lobe = kBsdfGlossyReflection;
        s.weight = specular_reflectance_->eval(hit) * fresnel_conductor(wi_m, ior_) * g;
        return s;
    }

    Color eval(const Hit& hit, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return Color(0.f);
        const Vec3 h = normalize(wi + wo);
        const float d = distr_.D(h);
        if (d == 0.f) return Color(0.f);
        const float g = distr_.G1(wi, h) * distr_.G1(wo, h);
        return specular_reflectance_->eval(hit) * fresnel_conductor(dot(wi, h), ior_) *
               (d * g / (4.f * wi.z));
    }

    float pdf(const Hit&, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return 0.f;
        const Vec3 h = normalize(wi + wo);
        const float wo_h = dot(wo, h);
        if (!(dot(wi, h) > 0.f) || !(wo_h > 0.f)) return 0.f;
        return distr_.pdf(wi, h) / (4.f * wo_h);
    }

private:
    Microfacet distr_;
    ConductorIor ior_;
    std::shared_ptr<Texture> specular_reflectance_;
};

}  // namespace

FEMTO_PLUGIN(RoughConductor, femto::PluginKind::Bsdf, "roughconductor",
             "Rough conductor: Beckmann/GGX microfacet model with complex Fresnel reflectance",
             {{"distribution", "string", "beckmann", "microfacet distribution: beckmann or ggx"},
              {"alpha", "float", "0.1", "isotropic roughness (RMS slope for beckmann)"},
              {"alpha_u", "float", "0.1", "anisotropic roughness along the tangent"},
              {"alpha_v", "float", "0.1", "anisotropic roughness along the bitangent"},
              {"sample_visible", "boolean", "true",
               "sample the visible normals (else the full distribution)"},
              {"material", "string", "none",
               "conductor preset (Au, Ag, Al, Cu, Cr, W, ...; \"none\" = ideal mirror)"},
              {"eta", "color", "0", "real part of the complex IOR (instead of a preset)"},
              {"k", "color", "1", "imaginary part (absorption) of the complex IOR"},
              {"ext_eta", "float|string", "1", "IOR of the exterior dielectric (number or name)"},
              {"specular_reflectance", "color|texture", "1",
               "factor on the reflection (physically 1)"}})
