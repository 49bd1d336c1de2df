// heterogeneous: a participating medium whose extinction varies in space, read from a volume
// (Mitsuba 0.6's and Mitsuba 3's `heterogeneous` medium):
//
//     sigma_t(p) = scale * density(p),   sigma_s(p) = albedo(p) * sigma_t(p)
//
// The density is a 1-channel volume given in any of the ways Mitsuba scenes write it:
//     <volume name="density" type="gridvolume"> ... </volume>     Mitsuba 0.6
//     <volume name="sigma_t" type="gridvolume"> ... </volume>     Mitsuba 3 (or constvolume)
//     <float name="sigma_t" value="2"/>                           Mitsuba 3: a constant
//     <string name="density" value="smoke.vol"/>                  femto's shorthand
// The shorthand is a `gridvolume` laid out as Mitsuba 0.6 lays it (the box stored in the file,
// data points on its faces: use_grid_bbox and the vertex lattice) and placed by the medium's
// `to_world`; the loader resolves the file name next to the scene file that names it. Without
// either, sigma_t is 1 (Mitsuba 3's default). `albedo` is a colour or a volume of 1 or 3
// channels in [0, 1], default 0.75 (Mitsuba 3's; Mitsuba 0.6 has none). `eta` and the nested
// <phase> are read by the Medium base class.
//
// transmittance() is an unbiased estimate by residual ratio tracking (Novak et al. 2014) with a
// constant control: the ray is clipped to the volume's region (transmittance is exactly 1
// outside), the control extinction mu_c = scale * min(density) is integrated exactly,
// exp(-mu_c L), and the residual sigma_t - mu_c is ratio-tracked with its majorant scale *
// (max - min) density. For grids whose minimum is 0 (most) this is plain ratio tracking with
// majorant(); a constant density gives the exact exp(-sigma_t L) with no random numbers drawn.
// Estimates that fall below 0.1 are Russian-rouletted (kept with probability T / 0.1, then
// worth 0.1), which is unbiased and bounds the work through thick media.
//
// A grid whose tracking would take more than 1e4 steps along a ray through it (scale *
// (largest - smallest density) times the longest chord through its box in the scene) is
// refused: one voxel of density 1e6 made a one-second render take minutes.
#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>

#include "femto/log.h"
#include "femto/medium.h"
#include "femto/plugin.h"
#include "femto/sampler.h"
#include "femto/transform.h"
#include "femto/volume.h"

namespace {

using femto::Color;
using femto::Properties;
using femto::Vec3;
using femto::Volume;

/// Largest expected number of ratio-tracking steps along a ray through the grid (residual
/// majorant x longest chord through the box).
constexpr double kMaxTrackingSteps = 1e4;
/// Ratio-tracking estimates below this are Russian-rouletted.
constexpr double kRouletteThreshold = 0.1;

template <typename T>
std::string to_str(const T& v) {
    std::ostringstream os;
    os << v;
    return os.str();
}

class HeterogeneousMedium final : public femto::Medium {
public:
    explicit HeterogeneousMedium(const Properties& props) : femto::Medium(props) {
        density_ = read_density(props);
        read_albedo(props);
        scale_ = props.get_float("scale", 1.0);
        if (!(scale_ >= 0.0) || !std::isfinite(scale_))
            props.fail("scale", "scale must be finite and >= 0, not " + to_str(scale_));
        read_mitsuba_options(props);

        min_sigma_ = scale_ * double(density_->min_value()[0]);
        max_sigma_ = scale_ * double(density_->max_value()[0]);
        // If the scale overflows a float (density * scale), the majorant would be infinite.
        if (!std::isfinite(static_cast<float>(max_sigma_)))
            props.fail("scale",
                       "scale * the largest density (" + to_str(max_sigma_) + ") overflows");
        residual_majorant_ = max_sigma_ - min_sigma_;
        check_tracking_work(props);
    }

    bool homogeneous() const override { return false; }

    float majorant() const override { return static_cast<float>(max_sigma_); }

    Color sigma_t(const Vec3& p) const override {
        return Color(static_cast<float>(scale_ * density_->eval_1(p)));
    }

    Color sigma_s(const Vec3& p) const override {
        const float st = sigma_t(p)[0];
        return (constant_albedo_ ? albedo_ : albedo_volume_->eval(p)) * st;
    }

    Color transmittance(const femto::Ray& ray, double distance,
                        femto::Sampler& sampler) const override {
        double t0 = 0.0, t1 = distance;
        if (!(t1 > 0.0) || !density_->clip(ray, t0, t1)) return Color(1.f);

        double tr = min_sigma_ > 0.0 ? std::exp(-min_sigma_ * (t1 - t0)) : 1.0;
        if (!(residual_majorant_ > 0.0) || tr == 0.0) return Color(static_cast<float>(tr));
        const double inv_majorant = 1.0 / residual_majorant_;
        double t = t0;
        for (;;) {
            const double u = sampler.next_1d();
            t -= std::log1p(-std::min(u, 1.0 - 1e-16)) * inv_majorant;
            if (!(t < t1)) break;
            const Vec3 p(float(ray.o.x + double(ray.d.x) * t), float(ray.o.y + double(ray.d.y) * t),
                         float(ray.o.z + double(ray.d.z) * t));
            // 1 - (sigma_t - mu_c) / (max - mu_c), written so that it is exactly 0 at the max.
            tr *= std::clamp((max_sigma_ - scale_ * density_->eval_1(p)) * inv_majorant, 0.0, 1.0);
            if (tr < kRouletteThreshold) {
                if (tr <= 0.0 || sampler.next_1d() >= tr / kRouletteThreshold) return Color(0.f);
                tr = kRouletteThreshold;
            }
        }
        return Color(static_cast<float>(tr));
    }

private:
    // `density` (Mitsuba 0.6, or femto's file-name shorthand) or `sigma_t` (Mitsuba 3).
    static std::shared_ptr<Volume> read_density(const Properties& props) {
        if (props.has("density") && props.has("sigma_t"))
            props.fail("sigma_t",
                       "give the density once: as density (Mitsuba 0.6) or as sigma_t "
                       "(Mitsuba 3), not both");
        const std::string name = props.has("density") ? "density" : "sigma_t";
        const bool file = props.has("density") && props.type("density") == Properties::Type::String;
        if (props.has("to_world") && !file)
            props.fail("to_world",
                       "to_world places a density grid given by its file name (<string "
                       "name=\"density\">); a nested <volume> takes its own to_world");
        std::shared_ptr<Volume> v =
            file ? grid_from_file(props) : femto::get_volume(props, name, Color(1.f));
        if (v->channels() != 1)
            props.fail(name, "\"" + name + "\" has " + std::to_string(v->channels()) +
                                 " channels; femto's heterogeneous medium has one extinction "
                                 "for all colours, so its density needs 1 channel");
        return v;
    }

    // The shorthand <string name="density" value="x.vol"/>: a gridvolume laid out as in
    // Mitsuba 0.6, whose errors are located at the string.
    static std::shared_ptr<Volume> grid_from_file(const Properties& props) {
        const femto::SourceLocation at = props.location_of("density");
        Properties grid("gridvolume", props.location());
        grid.set("filename", Properties::Type::String, props.get_string("density"), at);
        grid.set("use_grid_bbox", Properties::Type::Bool, true, at);
        grid.set("lattice", Properties::Type::String, std::string("vertex"), at);
        if (props.has("to_world"))
            grid.set("to_world", Properties::Type::Transform, props.get_transform("to_world"),
                     props.location_of("to_world"));
        return std::static_pointer_cast<Volume>(
            femto::create_child_object(femto::PluginKind::Volume, "gridvolume", grid));
    }

    void read_albedo(const Properties& props) {
        albedo_volume_ = femto::get_volume(props, "albedo", Color(0.75f));
        const Color hi = albedo_volume_->max_value();
        for (int c = 0; c < 3; ++c)
            if (!(hi[c] <= 1.f))
                props.fail("albedo",
                           "albedo (the single-scattering albedo) must lie in [0, 1] in every "
                           "channel, not " +
                               to_str(hi[c]));
        constant_albedo_ = albedo_volume_->is_constant();
        if (constant_albedo_) albedo_ = albedo_volume_->eval(Vec3(0.f));
    }

    // Mitsuba's switches for its own estimators: accepted, with a note where femto differs.
    static void read_mitsuba_options(const Properties& props) {
        const std::string method = props.get_string("method", "woodcock");
        if (method == "simpson")
            femto::log_note(props.location_of("method"),
                            "heterogeneous: method \"simpson\" (Mitsuba 0.6's biased quadrature) "
                            "is not used: femto tracks media by unbiased ratio tracking");
        else if (method != "woodcock")
            props.fail("method", "unknown method \"" + method + "\"; valid: woodcock, simpson");
        if (props.has("step_size") && props.get_float("step_size") > 0.0)
            femto::log_note(props.location_of("step_size"),
                            "heterogeneous: step_size is ignored (it sets Mitsuba 0.6's "
                            "quadrature step; femto tracks media by ratio tracking)");
        if (!props.get_bool("sample_emitters", true))
            femto::log_note(props.location_of("sample_emitters"),
                            "heterogeneous: sample_emitters=false is ignored: femto's "
                            "integrators always sample emitters from medium vertices");
        props.get_bool("has_spectral_extinction", true);  // one extinction for all colours here
    }

    // Ratio tracking takes about residual majorant x chord steps along a ray through the box
    // (more where the grid is nearly empty: nothing ends the walk early). A voxel of density
    // 1e6 made renders of a second take minutes; such grids are refused.
    void check_tracking_work(const Properties& props) const {
        if (!(residual_majorant_ > 0.0)) return;  // constant: no tracking at all
        const double chord = density_->longest_chord();
        const double steps = residual_majorant_ * chord;
        if (!(steps <= kMaxTrackingSteps))
            props.fail("scale",
                       "the density grid's majorant (scale * (largest - smallest density) = " +
                           to_str(residual_majorant_) +
                           " per scene unit) times the longest chord "
                           "through its box (" +
                           to_str(chord) + " scene units) is " + to_str(steps) +
                           ": tracking a ray through it would take about that many density "
                           "lookups, and femto accepts at most " +
                           to_str(kMaxTrackingSteps) +
                           " (lower the scale, or the densities, of the grid)");
    }

    std::shared_ptr<Volume> density_, albedo_volume_;
    bool constant_albedo_ = true;
    Color albedo_;
    double scale_ = 1.0;
    double min_sigma_ = 0, max_sigma_ = 0, residual_majorant_ = 0;
};

}  // namespace

FEMTO_PLUGIN(
    HeterogeneousMedium, femto::PluginKind::Medium, "heterogeneous",
    "Medium whose extinction varies in space (a density volume, e.g. a Mitsuba .vol grid); "
    "sigma_t = scale * density, sigma_s = albedo * sigma_t",
    {{"density", "filename|volume", "",
      "the density per scene unit, a 1-channel <volume> (Mitsuba 0.6), or the name of a .vol "
      "file laid out as Mitsuba 0.6 does (the file's box, data points on its faces)"},
     {"sigma_t", "float|volume", "1", "Mitsuba 3's name for the density (give one of the two)"},
     {"albedo", "color|volume", "0.75",
      "single-scattering albedo sigma_s / sigma_t, in [0, 1] (a colour or a volume)"},
     {"scale", "float", "1", "factor applied to the densities: sigma_t = scale * density"},
     {"to_world", "transform", "",
      "places the box of a density given by file name in the scene (none: as in the file)"},
     {"method", "string", "woodcock",
      "Mitsuba 0.6's tracking method: woodcock or simpson (femto always ratio-tracks)"},
     {"step_size", "float", "", "Mitsuba 0.6's quadrature step; ignored"},
     {"sample_emitters", "boolean", "true", "Mitsuba 3; femto always samples emitters"},
     {"has_spectral_extinction", "boolean", "true", "Mitsuba 3; ignored"}})
