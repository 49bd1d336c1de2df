// The Medium base class: what every participating medium reads.
#include "femto/medium.h"

#include <cmath>

#include "femto/plugin.h"
#include "femto/properties.h"

namespace femto {

std::vector<ParamSpec> Medium::inherited_params() {
    return inherit_params(
        Object::inherited_params(), "Medium",
        {{"eta", "float", "1", "index of refraction: light travels at c / eta inside"},
         {"phase", "phase", "isotropic", "phase function (nested <phase>)"}});
}

Medium::Medium(const Properties& props) {
    eta_ = props.get_float("eta", 1.0);
    if (!(eta_ >= 1.0) || !std::isfinite(eta_))
        props.fail("eta", "eta (the medium's index of refraction) must be finite and >= 1");
    phase_ = std::static_pointer_cast<PhaseFunction>(props.child(PluginKind::Phase, "isotropic"));
}

}  // namespace femto
