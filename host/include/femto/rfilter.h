// femto public API: image reconstruction filters (<rfilter>), separable in x and y.
#pragma once

#include "femto/object.h"

namespace femto {

class ReconstructionFilter : public Object {
public:
    PluginKind kind() const override { return PluginKind::ReconstructionFilter; }
    /// Half-width of the support, in pixels.
    virtual float radius() const = 0;
    /// 1-D filter weight at offset `x` (pixels) from the pixel centre; 0 outside the radius.
    virtual float eval(float x) const = 0;
};

}  // namespace femto
