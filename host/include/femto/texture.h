// femto public API: textures (spatially varying colours).
#pragma once

#include <memory>

#include "femto/color.h"
#include "femto/object.h"
#include "femto/properties.h"
#include "femto/shape.h"

namespace femto {

class Texture : public Object {
public:
    PluginKind kind() const override { return PluginKind::Texture; }
    virtual Color eval(const Hit& hit) const = 0;
    /// Mean value over the texture's domain (used for sampling weights and previews).
    virtual Color mean() const = 0;
    /// True when eval() is the same everywhere.
    virtual bool is_constant() const { return false; }
};

class ConstantTexture final : public Texture {
public:
    explicit ConstantTexture(const Color& c) : value_(c) {}
    Color eval(const Hit&) const override { return value_; }
    Color mean() const override { return value_; }
    bool is_constant() const override { return true; }

private:
    Color value_;
};

/// Reads parameter `name` as a colour (rgb/srgb/spectrum/float) or a nested texture.
/// Missing -> a constant `def`. Textures are reflectances and colours: a negative constant is
/// a located SceneError (it would make negative radiance).
std::shared_ptr<Texture> get_texture(const Properties& props, const std::string& name,
                                     const Color& def);

}  // namespace femto
