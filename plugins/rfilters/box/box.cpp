// box: the box reconstruction filter of Mitsuba (radius 0.5 pixel, weight 1 inside).
//
// The support is half-open: a sample on the boundary between two pixels counts for exactly one
// of them, the pixel it was taken for. Pixel i's samples lie in [i, i + 1), at offsets x = centre
// - position in (-0.5, 0.5].
#include "femto/plugin.h"
#include "femto/rfilter.h"

namespace {

class BoxFilter final : public femto::ReconstructionFilter {
public:
    explicit BoxFilter(const femto::Properties&) {}
    float radius() const override { return 0.5f; }
    float eval(float x) const override { return (x > -0.5f && x <= 0.5f) ? 1.f : 0.f; }
};

}  // namespace

FEMTO_PLUGIN(BoxFilter, femto::PluginKind::ReconstructionFilter, "box",
             "Box filter: weight 1 within half a pixel of the centre", {})
