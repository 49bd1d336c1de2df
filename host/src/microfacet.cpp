// Microfacet distributions (femto/microfacet.h): evaluation, Smith shadowing-masking and
// sampling, shared by the rough materials.
#include "femto/microfacet.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <string>

namespace femto {

namespace {

std::string to_lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

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

/// Visible slopes of the alpha = 1 Beckmann surface seen from (sin_t, 0, cos_t) (not
/// necessarily normalised). The x slope has the CDF
///   C(b) = (1 + b + tan_t / sqrt(pi) exp(-erfinv(b)^2)) / (1 + c + tan_t / sqrt(pi)
///   exp(-cot_t^2))
/// over b = erf(slope) in [-1, c = erf(cot_t)], inverted by Newton steps that fall back to
/// bisection whenever a step leaves the bracket; the y slope is a unit Gaussian.
void sample_visible_11_beckmann(double sin_t, double cos_t, Vec2 u, double& slope_x,
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

}  // namespace

Microfacet::Microfacet(MicrofacetType type, float alpha_u, float alpha_v, bool sample_visible)
    : type_(type),
      au_(std::max(alpha_u, kMinMicrofacetAlpha)),
      av_(std::max(alpha_v, kMinMicrofacetAlpha)),
      visible_(sample_visible) {}

float Microfacet::D(const Vec3& m) const {
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

float Microfacet::G1(const Vec3& v, const Vec3& m) const {
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

bool Microfacet::sample(const Vec3& wi, Vec2 u, Vec3& m) const {
    if (visible_) {
        m = type_ == MicrofacetType::GGX ? sample_visible_ggx(wi, u)
                                         : sample_visible_beckmann(wi, u);
    } else {
        m = sample_full(u);
    }
    return is_finite(m) && m.z > 0.f;
}

/// Heitz 2018, "Sampling the GGX Distribution of Visible Normals".
Vec3 Microfacet::sample_visible_ggx(const Vec3& wi, Vec2 u) const {
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
Vec3 Microfacet::sample_visible_beckmann(const Vec3& wi, Vec2 u) const {
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
    return {static_cast<float>(-rx * inv), static_cast<float>(-ry * inv), static_cast<float>(inv)};
}

/// Samples D(m) cos(theta_m) (Walter et al. 2007; anisotropic azimuth as Mitsuba).
Vec3 Microfacet::sample_full(Vec2 u) const {
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
            cos_phi = std::copysign(1.0 / std::sqrt(tmp * tmp + 1.0), std::abs(u.y - 0.5) - 0.25);
            sin_phi = cos_phi * tmp;
        } else {
            cos_phi = 0.0;
            sin_phi = u.y < 0.5 ? 1.0 : -1.0;
        }
        alpha2 = 1.0 / ((cos_phi / au_) * (cos_phi / au_) + (sin_phi / av_) * (sin_phi / av_));
    }
    const double tan2 =
        type_ == MicrofacetType::Beckmann ? -alpha2 * std::log1p(-ux) : alpha2 * ux / (1.0 - ux);
    const double cos_t = 1.0 / std::sqrt(1.0 + tan2);
    const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
    return {static_cast<float>(sin_t * cos_phi), static_cast<float>(sin_t * sin_phi),
            static_cast<float>(cos_t)};
}
MicrofacetType read_microfacet_type(const Properties& props) {
    const std::string dist = to_lower(props.get_string("distribution", "beckmann"));
    if (dist == "beckmann") return MicrofacetType::Beckmann;
    if (dist == "ggx") return MicrofacetType::GGX;
    if (dist == "phong" || dist == "as")
        props.fail("distribution", "microfacet distribution \"" + dist +
                                       "\" (Mitsuba 0.6) is not available in femto; valid: "
                                       "beckmann, ggx (a Phong exponent e is close to beckmann "
                                       "with alpha = sqrt(2 / (e + 2)))");
    props.fail("distribution",
               "unknown microfacet distribution \"" + dist + "\"; valid: beckmann, ggx");
}

Microfacet read_microfacet(const Properties& props) {
    const MicrofacetType type = read_microfacet_type(props);
    double au, av;
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
    } else {
        au = av = props.get_float("alpha", 0.1);
    }
    const bool visible = props.get_bool("sample_visible", true);
    return Microfacet(type, static_cast<float>(au), static_cast<float>(av), visible);
}

}  // namespace femto
