// Emission in time: the pulse profile every emitter carries.
#include "femto/emitter.h"

#include <fmt/format.h>

#include <cmath>

#include "femto/medium.h"

namespace femto {

namespace {
// Standard normal quantile: Newton iterations on the exact CDF (std::erfc) from a logistic
// start; converges to double precision for u in (1e-300, 1).
double normal_quantile(double u) {
    if (!(u > 0)) return -38.0;
    if (!(u < 1)) return 38.0;
    double x = std::log(u / (1 - u)) / 1.702;
    for (int i = 0; i < 60; ++i) {
        const double cdf = 0.5 * std::erfc(-x / std::sqrt(2.0));
        const double pdf = std::exp(-0.5 * x * x) / std::sqrt(2 * M_PI);
        if (!(pdf > 0)) break;
        const double step = (cdf - u) / pdf;
        x -= std::clamp(step, -2.0, 2.0);
        if (std::abs(step) < 1e-14 * std::max(1.0, std::abs(x))) break;
    }
    return x;
}
}  // namespace

double PulseProfile::sample(float u) const {
    switch (shape) {
        case Shape::Delta:
            return offset;
        case Shape::Box:
            return offset + width * double(u);
        case Shape::Gaussian:
            return offset + sigma * normal_quantile(double(u) + 0x1p-25);
    }
    return offset;
}

double PulseProfile::pdf(double t) const {
    switch (shape) {
        case Shape::Delta:
            return t == offset ? INFINITY : 0.0;
        case Shape::Box:
            return t >= offset && t <= offset + width ? 1.0 / width : 0.0;
        case Shape::Gaussian: {
            const double z = (t - offset) / sigma;
            return std::exp(-0.5 * z * z) / (sigma * std::sqrt(2 * M_PI));
        }
    }
    return 0.0;
}

double PulseProfile::earliest() const {
    return shape == Shape::Gaussian ? offset - 6 * sigma : offset;
}

double PulseProfile::mean() const { return shape == Shape::Box ? offset + 0.5 * width : offset; }

std::vector<ParamSpec> Emitter::inherited_params() {
    return inherit_params(
        Object::inherited_params(), "Emitter",
        {{"pulse", "string", "delta", "emission profile in time: delta, box or gaussian"},
         {"pulse_width", "float", "", "box pulse length (optical path length, scene units)"},
         {"pulse_sigma", "float", "", "gaussian pulse deviation (optical path length)"},
         {"time_offset", "float", "0", "emission start (delta/box) or mean (gaussian), same units"},
         {"medium", "medium", "", "medium the emitter sits in (nested <medium> or <ref>)"}});
}

Emitter::Emitter(const Properties& props) {
    medium_ = std::static_pointer_cast<Medium>(props.child(PluginKind::Medium));
    const std::string shape = props.get_string("pulse", "delta");
    pulse_.offset = props.get_float("time_offset", 0.0);
    if (shape == "delta") {
        pulse_.shape = PulseProfile::Shape::Delta;
    } else if (shape == "box") {
        pulse_.shape = PulseProfile::Shape::Box;
        pulse_.width = props.get_float("pulse_width");
        if (!(pulse_.width > 0)) props.fail("pulse_width", "pulse_width must be > 0");
    } else if (shape == "gaussian") {
        pulse_.shape = PulseProfile::Shape::Gaussian;
        pulse_.sigma = props.get_float("pulse_sigma");
        if (!(pulse_.sigma > 0)) props.fail("pulse_sigma", "pulse_sigma must be > 0");
    } else {
        props.fail("pulse", fmt::format("pulse must be delta, box or gaussian, not \"{}\"", shape));
    }
    if (shape != "box" && props.has("pulse_width"))
        props.fail("pulse_width", "pulse_width applies to pulse=\"box\" only");
    if (shape != "gaussian" && props.has("pulse_sigma"))
        props.fail("pulse_sigma", "pulse_sigma applies to pulse=\"gaussian\" only");
}

Color Emitter::read_emission(const Properties& props, const std::string& name, const Color& def) {
    const Color c = props.get_color(name, def);
    for (int i = 0; i < 3; ++i) {
        if (c[i] < 0) props.fail(name, fmt::format("the {} must not be negative", name));
        if (!(c[i] <= kMaxEmission))
            props.fail(name, fmt::format("the {} ({:g}) is beyond femto's limit of {:g}: renders "
                                         "multiply and sum it in single precision, where it would "
                                         "overflow to infinity",
                                         name, c[i], kMaxEmission));
    }
    return c;
}

}  // namespace femto
