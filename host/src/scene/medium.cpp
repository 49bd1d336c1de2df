// The Medium base class: what every participating medium reads.
#include "femto/medium.h"

#include <cmath>

#include "femto/plugin.h"
#include "femto/properties.h"

namespace femto {

Medium::Medium(const Properties& props) {
    eta_ = props.get_float("eta", 1.0);
    if (!(eta_ >= 1.0) || !std::isfinite(eta_))
        props.fail("eta", "eta (the medium's index of refraction) must be finite and >= 1");
    phase_ = std::static_pointer_cast<PhaseFunction>(props.child(PluginKind::Phase, "isotropic"));
}

}  // namespace femto
