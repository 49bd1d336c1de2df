// constvolume: the same value everywhere (Mitsuba 0.6's and Mitsuba 3's `constvolume`), as a
// medium's density or albedo. A grey value is a scalar (1 channel, what a density must be), any
// other colour has 3 channels.
//
// Its region is all of space: a medium it fills is bounded by the shapes that name the medium.
// (Mitsuba 3 also ends a heterogeneous medium at its sigma_t volume's box, the unit cube under
// that volume's to_world even for a constvolume; femto's constvolume has no box.)
#include <sstream>
#include <string>

#include "femto/plugin.h"
#include "femto/volume.h"

namespace {

using femto::Color;
using femto::Properties;

Color read_value(const Properties& props) {
    const Color v = props.get_color("value", Color(1.f));
    if (!(v.r >= 0.f && v.g >= 0.f && v.b >= 0.f)) {
        std::ostringstream text;
        text << "a constvolume's value must be >= 0 in every channel (it is a density or an "
                "albedo), not ("
             << v.r << ", " << v.g << ", " << v.b << ")";
        props.fail("value", text.str());
    }
    return v;
}

class ConstVolume final : public femto::ConstantVolume {
public:
    explicit ConstVolume(const Properties& props) : ConstVolume(read_value(props)) {}

private:
    explicit ConstVolume(const Color& v)
        : femto::ConstantVolume(v, v.r == v.g && v.g == v.b ? 1 : 3) {}
};

}  // namespace

FEMTO_PLUGIN(ConstVolume, femto::PluginKind::Volume, "constvolume",
             "The same value everywhere (a density, or an albedo colour)",
             {{"value", "color", "1",
               "the value: a float or a grey colour (1 channel), or a colour (3 channels), >= 0"}})
