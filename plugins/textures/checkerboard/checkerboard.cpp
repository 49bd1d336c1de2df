// checkerboard: Mitsuba 3's checkerboard texture. The surface uv, mapped through `to_uv`
// (applied to the point (u, v, 0)), is wrapped to [0, 1)^2; the texture is `color0` where
// both coordinates are on the same side of 0.5 and `color1` elsewhere: a 2 x 2 checker per
// unit square. Both colours may be nested textures, evaluated at the same hit.
#include <cmath>
#include <memory>

#include "femto/plugin.h"
#include "femto/texture.h"
#include "femto/transform.h"

namespace {

class Checkerboard final : public femto::Texture {
public:
    explicit Checkerboard(const femto::Properties& props)
        : color0_(femto::get_texture(props, "color0", femto::Color(0.4f))),
          color1_(femto::get_texture(props, "color1", femto::Color(0.2f))),
          to_uv_(props.get_transform("to_uv", femto::Transform())),
          identity_(to_uv_.is_identity()) {}

    femto::Color eval(const femto::Hit& hit) const override {
        float u = hit.uv.x, v = hit.uv.y;
        if (!identity_) {
            const femto::Vec3 p = to_uv_.point(femto::Vec3(u, v, 0.f));
            u = p.x;
            v = p.y;
        }
        u -= std::floor(u);
        v -= std::floor(v);
        return ((u > 0.5f) == (v > 0.5f)) ? color0_->eval(hit) : color1_->eval(hit);
    }

    femto::Color mean() const override { return (color0_->mean() + color1_->mean()) * 0.5f; }

private:
    std::shared_ptr<femto::Texture> color0_, color1_;
    femto::Transform to_uv_;
    bool identity_ = true;
};

}  // namespace

FEMTO_PLUGIN(Checkerboard, femto::PluginKind::Texture, "checkerboard",
             "Checkerboard of two colours, 2 x 2 squares per unit of uv (Mitsuba 3)",
             {{"color0", "color|texture", "0.4",
               "value where u and v (wrapped to [0,1)) are both <= 0.5 or both > 0.5"},
              {"color1", "color|texture", "0.2", "value on the other squares"},
              {"to_uv", "transform", "identity", "transform applied to the point (u, v, 0)"}})
