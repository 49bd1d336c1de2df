// plastic: a smooth dielectric coating over a diffuse base (Mitsuba's `plastic`).
//
// Light is either reflected specularly by the coating (a delta lobe with the dielectric
// Fresnel reflectance F(cos_i)), or refracted into it, scattered by the Lambertian base and
// bounced between base and coating until it leaves. Summing the internal bounces in closed
// form (Mitsuba's model) gives the non-delta part
//   f cos_o = (1 - F(cos_i)) (1 - F(cos_o)) / eta^2 * R / (1 - Fdr_int) * cos_o / pi,
// with Fdr_int the diffuse Fresnel reflectance of the coating seen from inside, and R the
// diffuse_reflectance (or, with nonlinear = true, R / (1 - R Fdr_int) instead of
// R / (1 - Fdr_int), which lets the internal bounces shift the colour).
//
// sample() chooses the specular lobe with probability proportional to F(cos_i) s and the
// diffuse one with probability proportional to (1 - F(cos_i)) d, where s and d are the mean
// specular and diffuse reflectances normalised to sum to one (as Mitsuba does). pdf() is the
// diffuse lobe's density times its selection probability. One-sided (as Mitsuba).
//
// Fdr is computed by numerical integration of the exact Fresnel term (as Mitsuba 0.6 does;
// Mitsuba 3 uses polynomial fits). With it, eta^2 (1 - Fdr_int) = 1 - Fdr_ext holds to
// integration accuracy, so a white plastic (diffuse and specular reflectance 1) reflects
// exactly all light: F + (1 - F) = 1, which the furnace test checks.
#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include "femto/bsdf.h"
#include "femto/fresnel.h"
#include "femto/plugin.h"
#include "femto/texture.h"
#include "femto/warp.h"

namespace {

using namespace femto;

/// Unpolarised dielectric Fresnel reflectance in double precision, for light arriving with
/// cosine mu > 0 at an interface of relative index eta (transmitted side over incident side).
double fresnel_reflectance_d(double mu, double eta) {
    const double cos_t2 = 1.0 - (1.0 - mu * mu) / (eta * eta);
    if (cos_t2 <= 0.0) return 1.0;
    const double ct = std::sqrt(cos_t2);
    const double a_s = (mu - eta * ct) / (mu + eta * ct);
    const double a_p = (ct - eta * mu) / (ct + eta * mu);
    return 0.5 * (a_s * a_s + a_p * a_p);
}

/// Composite Simpson rule over [0, 1] with n (even) intervals.
template <typename F>
double simpson01(F f, int n) {
    const double h = 1.0 / n;
    double sum = f(0.0) + f(1.0);
    for (int i = 1; i < n; ++i) sum += f(i * h) * (i % 2 ? 4.0 : 2.0);
    return sum * h / 3.0;
}

/// Diffuse Fresnel reflectance Fdr(eta) = (1/pi) * integral of F cos over the hemisphere
/// = 2 * integral_0^1 F(mu) mu dmu. For eta > 1 the integrand is smooth in mu. For eta < 1,
/// F = 1 below the critical cosine mu_c = sqrt(1 - eta^2), which contributes mu_c^2 exactly;
/// the rest is integrated over the refracted cosine t (mu dmu = eta^2 t dt), in which the
/// integrand is smooth (in mu it has a square-root kink at mu_c). Simpson with 2048
/// intervals on these smooth integrands is accurate to ~1e-12.
double fresnel_diffuse_reflectance(double eta) {
    if (eta == 1.0) return 0.0;
    constexpr int kIntervals = 2048;
    if (eta > 1.0)
        return 2.0 * simpson01([&](double mu) { return fresnel_reflectance_d(mu, eta) * mu; },
                               kIntervals);
    const double mu_c2 = 1.0 - eta * eta;
    const double rest = simpson01(
        [&](double t) {
            const double mu = std::sqrt(1.0 - eta * eta * (1.0 - t * t));
            return fresnel_reflectance_d(mu, eta) * t;
        },
        kIntervals);
    return mu_c2 + 2.0 * eta * eta * rest;
}

class Plastic final : public Bsdf {
public:
    explicit Plastic(const Properties& props)
        : diffuse_reflectance_(get_texture(props, "diffuse_reflectance", Color(0.5f))),
          specular_reflectance_(get_texture(props, "specular_reflectance", Color(1.f))),
          nonlinear_(props.get_bool("nonlinear", false)) {
        const float int_ior = read_ior(props, "int_ior", "polypropylene");
        const float ext_ior = read_ior(props, "ext_ior", "air");
        eta_ = int_ior / ext_ior;
        inv_eta2_ = 1.f / (eta_ * eta_);
        fdr_int_ = static_cast<float>(fresnel_diffuse_reflectance(1.0 / eta_));
        const float d_mean = diffuse_reflectance_->mean().average();
        const float s_mean = specular_reflectance_->mean().average();
        specular_weight_ = d_mean + s_mean > 0.f ? s_mean / (d_mean + s_mean) : 0.5f;
    }

    uint32_t flags() const override { return kBsdfDeltaReflection | kBsdfDiffuseReflection; }

    BsdfSample sample(const Hit& hit, const Vec3& wi, float u_lobe, Vec2 u) const override {
        BsdfSample s;
        if (wi.z <= 0.f) return s;
        const float f_i = fresnel_dielectric(wi.z, eta_).r;
        const float p_spec = specular_probability(f_i);
        if (u_lobe < p_spec) {
            s.wo = Vec3(-wi.x, -wi.y, wi.z);
            s.pdf = p_spec;
            s.eta = 1.f;
            s.sampled_lobe = kBsdfDeltaReflection;
            s.weight = specular_reflectance_->eval(hit) * (f_i / p_spec);
            return s;
        }
        const Vec3 wo = warp::square_to_cosine_hemisphere(u);
        const float p_diff = 1.f - p_spec;
        const float pdf = p_diff * warp::cosine_hemisphere_pdf(wo);
        if (!(pdf > 0.f)) return s;
        const float f_o = fresnel_dielectric(wo.z, eta_).r;
        s.wo = wo;
        s.pdf = pdf;
        s.eta = 1.f;
        s.sampled_lobe = kBsdfDiffuseReflection;
        // (diffuse * cos_o / pi) / (p_diff * cos_o / pi)
        s.weight = diffuse(hit) * (inv_eta2_ * (1.f - f_i) * (1.f - f_o) / p_diff);
        return s;
    }

    Color eval(const Hit& hit, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return Color(0.f);
        const float f_i = fresnel_dielectric(wi.z, eta_).r;
        const float f_o = fresnel_dielectric(wo.z, eta_).r;
        return diffuse(hit) *
               (warp::cosine_hemisphere_pdf(wo) * inv_eta2_ * (1.f - f_i) * (1.f - f_o));
    }

    float pdf(const Hit&, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return 0.f;
        const float f_i = fresnel_dielectric(wi.z, eta_).r;
        return (1.f - specular_probability(f_i)) * warp::cosine_hemisphere_pdf(wo);
    }

private:
    float specular_probability(float f_i) const {
        const float p_spec = f_i * specular_weight_;
        const float p_diff = (1.f - f_i) * (1.f - specular_weight_);
        return p_spec + p_diff > 0.f ? p_spec / (p_spec + p_diff) : 0.f;
    }

    /// The base's reflectance including the internal bounces under the coating.
    Color diffuse(const Hit& hit) const {
        const Color d = diffuse_reflectance_->eval(hit);
        if (nonlinear_) return d / (Color(1.f) - d * fdr_int_);
        return d / (1.f - fdr_int_);
    }

    std::shared_ptr<Texture> diffuse_reflectance_, specular_reflectance_;
    bool nonlinear_ = false;
    float eta_ = 1.f, inv_eta2_ = 1.f, fdr_int_ = 0.f, specular_weight_ = 0.5f;
};

}  // namespace

FEMTO_PLUGIN(Plastic, femto::PluginKind::Bsdf, "plastic",
             "Smooth plastic: dielectric coating (delta reflection) over a diffuse base",
             {{"diffuse_reflectance", "color|texture", "0.5", "reflectance of the diffuse base"},
              {"specular_reflectance", "color|texture", "1",
               "factor on the coating's reflection (physically 1)"},
              {"int_ior", "float|string", "polypropylene",
               "index of refraction of the coating (number or name)"},
              {"ext_ior", "float|string", "air", "exterior index of refraction (number or name)"},
              {"nonlinear", "boolean", "false",
               "let internal scattering shift the diffuse colour (Mitsuba's nonlinear)"}})
