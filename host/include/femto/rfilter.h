// femto public API: image reconstruction filters (<rfilter>), separable in x and y.
#pragma once

#include "femto/object.h"

namespace femto {

class ReconstructionFilter : public Object {
public:
    PluginKind kind() const override { return PluginKind::ReconstructionFilter; }
    /// Half-width of the support, in pixels.
    virtual float radius() const = 0;
    /// 1-D filter weight of a sample at offset `x` = (pixel centre - sample position), in
    /// pixels; 0 outside the radius. (The renderer's samples for pixel i lie in [i, i + 1),
    /// offsets (-0.5, 0.5] from its centre.)
    virtual float eval(float x) const = 0;
};

}  // namespace femto
