// moment: the first and second moments of nested integrators' samples as AOVs (Mitsuba 3's
// `moment`).
//
// Takes one or more nested <integrator>s and runs each on every camera sample, in document
// order, from the same sampler: the first consumes the sample's random numbers exactly as it
// would alone, so its image is the one it renders without `moment`, and the others continue
// the stream. The film's image is the first nested integrator's (every contribution at its own
// time). For nested integrator NAME (its `name` attribute, or _arg_0, _arg_1, ... for unnamed
// ones, as Mitsuba 3 names them) the sample's radiance, converted to CIE XYZ as Mitsuba 3's RGB
// variants do, is reported as AOV channels NAME.X, NAME.Y, NAME.Z (the first moment, once the
// film averages them) and its square as m2_NAME.X, ... (the second moment): all first moments
// first, then all second moments, in Mitsuba 3's order. With a box filter the film's averages
// are the plain means, so m2 - m1^2 is the per-sample variance of that channel (divide by the
// sample count for the variance of the pixel estimate); with another filter they are
// filter-weighted means.
//
// Moments are per camera sample, so the nested integrators must take camera samples without
// splatting (path, volpath, transient_path, direct, transient_ppm), and a steady film must
// record them (hdrfilm); a transient or streak film refuses the AOVs (Mitsuba 3's moment is
// steady too). The sensor's ray weight (Sensor::ray_weight(), applied by the renderer to the
// radiance) is applied to the moments here: AOVs are not scaled by the renderer.
#include <memory>
#include <string>
#include <vector>

#include "femto/integrator.h"
#include "femto/plugin.h"
#include "femto/sensor.h"

namespace {

using namespace femto;

// Linear Rec.709 RGB (D65) to CIE XYZ.
Vec3 rgb_to_xyz(const Color& c) {
    return {0.412453f * c.r + 0.357580f * c.g + 0.180423f * c.b,
            0.212671f * c.r + 0.715160f * c.g + 0.072169f * c.b,
            0.019334f * c.r + 0.119193f * c.g + 0.950227f * c.b};
}

class Moment final : public Integrator {
public:
    explicit Moment(const Properties& props) {
        for (const Properties::Entry& e : props.entries()) {
            if (e.type != Properties::Type::Object) continue;
            const auto& obj = std::get<ObjectPtr>(e.value);
            if (!obj || obj->kind() != PluginKind::Integrator) continue;
            auto nested = std::static_pointer_cast<Integrator>(obj);
            check_nested(props, e.name, *nested);
            for (const char* axis : {".X", ".Y", ".Z"}) names_.push_back(e.name + axis);
            nested_.push_back(std::move(nested));
        }
        props.objects(PluginKind::Integrator);  // marks them read
        if (nested_.empty())
            props.fail("integrator", "moment needs at least one nested <integrator>");
        const size_t first = names_.size();
        for (size_t i = 0; i < first; ++i) names_.push_back("m2_" + names_[i]);
    }

    std::vector<std::string> aov_names() const override { return names_; }

    void preprocess(const Scene& scene) override {
        for (const auto& n : nested_) n->preprocess(scene);
    }
    void begin_pass(const Scene& scene, const PassInfo& pass) override {
        for (const auto& n : nested_) n->begin_pass(scene, pass);
    }
    uint32_t samples_per_pass() const override { return samples_per_pass_; }
    double time_reach() const override {
        double reach = 0.0;
        for (const auto& n : nested_) reach = std::max(reach, n->time_reach());
        return reach;
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& ray,
                ContributionList& out) const override {
        const float k = scene.sensor().ray_weight();
        const size_t half = names_.size() / 2;
        ContributionList other;
        for (size_t i = 0; i < nested_.size(); ++i) {
            ContributionList& list = i == 0 ? out : other;
            if (i > 0) {
                other.clear();
                other.set_sample_index(out.sample_index());
                other.set_film_position(out.film_position());
            }
            nested_[i]->sample(scene, sampler, ray, list);
            Color sum(0.f);
            for (const Contribution& c : list.items()) sum += c.radiance;
            const Vec3 xyz = rgb_to_xyz(sum * k);
            for (int a = 0; a < 3; ++a) {
                out.set_aov(3 * i + size_t(a), xyz[a]);
                out.set_aov(half + 3 * i + size_t(a), xyz[a] * xyz[a]);
            }
        }
    }

    std::vector<Accumulator> accumulators() override {
        std::vector<Accumulator> all;
        for (const auto& n : nested_)
            for (const Accumulator& a : n->accumulators()) all.push_back(a);
        return all;
    }

    std::vector<std::string> write(const std::string& out_base,
                                   const RenderInfo& info) const override {
        std::vector<std::string> paths;
        for (const auto& n : nested_)
            for (std::string& p : n->write(out_base, info)) paths.push_back(std::move(p));
        return paths;
    }

private:
    // A nested integrator must take camera samples that stay in their pixel, and report no AOVs
    // of its own; integrators with a fixed number of samples per pass must agree on it.
    void check_nested(const Properties& props, const std::string& name, const Integrator& n) {
        const auto refuse = [&](const std::string& why) {
            props.fail(name, "moment cannot nest the " + n.type_name() + " integrator: " + why);
        };
        if (n.source() != SampleSource::Camera || n.splats())
            refuse(
                "its samples start at the lights or splat to other pixels, and moments are "
                "taken per camera sample");
        if (!n.aov_names().empty()) refuse("it reports AOVs of its own");
        if (const uint32_t spp = n.samples_per_pass(); spp > 0) {
            if (samples_per_pass_ > 0 && samples_per_pass_ != spp)
                refuse(
                    "it needs another number of samples per pass than the integrator "
                    "before it");
            samples_per_pass_ = spp;
        }
    }

    std::vector<std::shared_ptr<Integrator>> nested_;
    std::vector<std::string> names_;
    uint32_t samples_per_pass_ = 0;
};

}  // namespace

FEMTO_PLUGIN(Moment, femto::PluginKind::Integrator, "moment",
             "First and second moments (XYZ) of nested integrators' samples as AOV channels; the "
             "image is the first nested integrator's",
             {{"*", "integrator", "",
               "one or more nested <integrator>s, each named by its `name` attribute (unnamed: "
               "_arg_0, _arg_1, ...), giving AOVs NAME.X/Y/Z and m2_NAME.X/Y/Z"}})
