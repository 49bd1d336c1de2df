// gaussian: the truncated Gaussian reconstruction filter of Mitsuba 3,
//     w(x) = max(0, exp(-x^2 / (2 s^2)) - exp(-r^2 / (2 s^2))),  r = 4 s,
// i.e. the Gaussian shifted down by its value at the radius so that it reaches 0 there
// continuously, and 0 outside [-r, r].
#include <cmath>
#include <string>

#include "femto/plugin.h"
#include "femto/rfilter.h"

namespace {

class GaussianFilter final : public femto::ReconstructionFilter {
public:
    explicit GaussianFilter(const femto::Properties& props) {
        const double s = props.get_float("stddev", 0.5);
        if (!(s > 0.0))
            props.fail("stddev", "\"stddev\" must be positive, got " + std::to_string(s));
        radius_ = static_cast<float>(4.0 * s);
        alpha_ = static_cast<float>(-1.0 / (2.0 * s * s));
        bias_ = std::exp(alpha_ * radius_ * radius_);
    }
    float radius() const override { return radius_; }
    float eval(float x) const override {
        if (!(std::abs(x) <= radius_)) return 0.f;
        const float w = std::exp(alpha_ * x * x) - bias_;
        return w > 0.f ? w : 0.f;
    }

private:
    float radius_ = 2.f;
    float alpha_ = -2.f;
    float bias_ = 0.f;
};

}  // namespace

FEMTO_PLUGIN(GaussianFilter, femto::PluginKind::ReconstructionFilter, "gaussian",
             "Gaussian filter truncated at 4 standard deviations (shifted to reach 0 there)",
             {{"stddev", "float", "0.5", "standard deviation in pixels (> 0); radius = 4 stddev"}})
