// tent: the tent (triangle) reconstruction filter of Mitsuba: w(x) = max(0, 1 - |x| / r).
// Its integral is r; films normalise by the sum of the weights, so no constant is needed.
#include <cmath>
#include <string>

#include "femto/plugin.h"
#include "femto/rfilter.h"

namespace {

class TentFilter final : public femto::ReconstructionFilter {
public:
    explicit TentFilter(const femto::Properties& props) {
        const double r = props.get_float("radius", 1.0);
        if (!(r > 0.0))
            props.fail("radius", "\"radius\" must be positive, got " + std::to_string(r));
        radius_ = static_cast<float>(r);
        inv_radius_ = static_cast<float>(1.0 / r);
    }
    float radius() const override { return radius_; }
    float eval(float x) const override {
        const float ax = std::abs(x);
        if (!(ax < radius_)) return 0.f;
        const float w = 1.f - ax * inv_radius_;
        return w > 0.f ? w : 0.f;
    }

private:
    float radius_ = 1.f;
    float inv_radius_ = 1.f;
};

}  // namespace

FEMTO_PLUGIN(TentFilter, femto::PluginKind::ReconstructionFilter, "tent",
             "Tent filter: weight 1 - |x|/radius",
             {{"radius", "float", "1", "half-width of the filter in pixels (> 0)"}})
