// Homogeneous participating medium: the same extinction sigma_t and scattering sigma_s
// everywhere (per colour channel, per scene unit of length), a phase function and an index of
// refraction eta (light travels at c / eta inside; thesis ch. 5.6).
//
// Coefficients, as Mitsuba: either `sigma_a` and `sigma_s`, or `sigma_t` and `albedo`
// (sigma_s = albedo * sigma_t; the default is Mitsuba 3's sigma_t = 1, albedo = 0.75), all
// multiplied by `scale` (0.x's densityMultiplier). Each may also be a nested constant
// <volume type="constvolume"> (Mitsuba 3 reads albedo and sigma_t as volumes, and scenes write
// them so); a volume that varies in space belongs in the heterogeneous medium.
#include <fmt/format.h>

#include <cmath>
#include <limits>

#include "femto/medium.h"
#include "femto/plugin.h"
#include "femto/volume.h"

namespace {

using namespace femto;

class Homogeneous final : public Medium {
public:
    explicit Homogeneous(const Properties& props) : Medium(props) {
        const bool absorbing = props.has("sigma_a") || props.has("sigma_s");
        const bool extinct = props.has("sigma_t") || props.has("albedo");
        if (absorbing && extinct)
            props.fail(props.has("sigma_t") ? "sigma_t" : "albedo",
                       "give either sigma_a and sigma_s, or sigma_t and albedo, not both");
        const double scale = props.get_float("scale", 1.0);
        if (!(scale >= 0.0) || !std::isfinite(scale))
            props.fail("scale", "scale must be finite and >= 0");
        // The products in double first: a scale beyond the float range (1e39 passes isfinite)
        // would make float(scale) undefined, and 0 * inf NaN.
        const auto scaled = [&](const Color& c, const char* name) {
            const double largest = double(std::max(c.r, std::max(c.g, c.b))) * scale;
            if (!(largest <= double(std::numeric_limits<float>::max())))
                props.fail(
                    props.has("scale") ? "scale" : name,
                    fmt::format("{} times scale is {:g}, beyond the float range", name, largest));
            return Color(float(c.r * scale), float(c.g * scale), float(c.b * scale));
        };
        if (absorbing) {
            const Color sa = checked(props, "sigma_a", Color(0.f));
            const Color ss = checked(props, "sigma_s", Color(0.f));
            sigma_s_ = scaled(ss, "sigma_s");
            sigma_t_ = scaled(sa + ss, "sigma_a + sigma_s");
        } else {
            const Color st = checked(props, "sigma_t", Color(1.f));
            const Color albedo = constant(props, "albedo", Color(0.75f));
            for (int c = 0; c < 3; ++c)
                if (!(albedo[c] >= 0.f && albedo[c] <= 1.f))
                    props.fail("albedo", "every channel of albedo must lie in [0, 1]");
            sigma_t_ = scaled(st, "sigma_t");
            sigma_s_ = sigma_t_ * albedo;
        }
        majorant_ = std::max(sigma_t_.r, std::max(sigma_t_.g, sigma_t_.b));
        grey_ = sigma_t_.r == sigma_t_.g && sigma_t_.g == sigma_t_.b;
    }

    bool homogeneous() const override { return true; }
    float majorant() const override { return majorant_; }
    Color sigma_t(const Vec3&) const override { return sigma_t_; }
    Color sigma_s(const Vec3&) const override { return sigma_s_; }
    Color transmittance(const Ray&, double distance, Sampler&) const override {
        // One exponential when the channels agree (most media; exp() was 5 % of BDPT's
        // instructions in fog with three of them).
        if (grey_) return Color(float(std::exp(-double(sigma_t_.r) * distance)));
        Color tr;
        for (int c = 0; c < 3; ++c) tr[c] = float(std::exp(-double(sigma_t_[c]) * distance));
        return tr;
    }

private:
    // A colour, or a nested volume that is the same everywhere.
    static Color constant(const Properties& props, const char* name, const Color& def) {
        if (!props.has(name) || props.type(name) != Properties::Type::Object)
            return props.get_color(name, def);
        const std::shared_ptr<Volume> v = get_volume(props, name, def);
        if (!v->is_constant())
            props.fail(name, fmt::format("a homogeneous medium takes a constant {}, not a <volume "
                                         "type=\"{}\"> that varies in space (use the "
                                         "heterogeneous medium)",
                                         name, v->type_name()));
        return v->eval(Vec3(0.f));
    }

    static Color checked(const Properties& props, const char* name, const Color& def) {
        const Color v = constant(props, name, def);
        if (!v.is_finite() || v.r < 0.f || v.g < 0.f || v.b < 0.f)
            props.fail(name, fmt::format("{} must be finite and >= 0 in every channel", name));
        return v;
    }

    Color sigma_t_, sigma_s_;
    float majorant_ = 0.f;
    bool grey_ = false;  // sigma_t the same in every channel
};

}  // namespace

FEMTO_PLUGIN(
    Homogeneous, femto::PluginKind::Medium, "homogeneous",
    "Homogeneous participating medium (constant coefficients, index of refraction eta)",
    {{"sigma_a", "color|volume", "", "absorption coefficient (1 / scene unit), with sigma_s"},
     {"sigma_s", "color|volume", "", "scattering coefficient (1 / scene unit), with sigma_a"},
     {"sigma_t", "color|volume", "1", "extinction coefficient, with albedo (instead of the above)"},
     {"albedo", "color|volume", "0.75", "single-scattering albedo sigma_s / sigma_t"},
     {"scale", "float", "1", "multiplies the coefficients (0.x: densityMultiplier)"}})
