// A test plugin of type "path", the name of a built-in integrator, for the plugin shadowing
// test (cli.plugin_shadowing): it renders every pixel as `value`, so an image tells which of
// the libraries named "path" a render used. Built twice, as shadow-plugins/a/path.so and
// shadow-plugins/b/path.so, with different defaults (SHADOW_VALUE).
#include <femto/integrator.h>
#include <femto/path_clock.h>
#include <femto/plugin.h>

namespace {

class ConstantPath final : public femto::Integrator {
public:
    explicit ConstantPath(const femto::Properties& props)
        : value_(float(props.get_float("value", SHADOW_VALUE))) {}

    void sample(const femto::Scene& scene, femto::Sampler&, const femto::Ray& ray,
                femto::ContributionList& out) const override {
        femto::PathClock clock(scene, out, ray.o);
        clock.record(femto::Color(value_));
    }

private:
    float value_;
};

}  // namespace

FEMTO_PLUGIN(ConstantPath, femto::PluginKind::Integrator, "path",
             "Test plugin shadowing the built-in path integrator (copy " SHADOW_COPY ")",
             {{"value", "float", SHADOW_VALUE_TEXT, "the radiance of every pixel"}})
