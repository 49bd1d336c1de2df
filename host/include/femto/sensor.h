// femto public API: sensors (cameras). A sensor owns its film and sampler.
#pragma once

#include <memory>

#include "femto/film.h"
#include "femto/math.h"
#include "femto/object.h"
#include "femto/properties.h"
#include "femto/sampler.h"
#include "femto/transform.h"

namespace femto {

class Medium;

class Sensor : public Object {
public:
    PluginKind kind() const override { return PluginKind::Sensor; }

    /// Primary ray through film position `pos` (pixels, origin top-left, +x right, +y down);
    /// `aperture` is for lenses. Returns a ray with a unit direction.
    virtual Ray sample_ray(Vec2 pos, Vec2 aperture) const = 0;

    Film& film() const { return *film_; }
    Sampler& sampler() const { return *sampler_; }
    const Transform& to_world() const { return to_world_; }
    /// The medium the sensor sits in (a nested <medium> or <ref>), or nullptr (vacuum).
    const Medium* medium() const { return medium_.get(); }

    /// The parameters the constructor reads, for the plugin schemas.
    static std::vector<ParamSpec> inherited_params();

protected:
    /// Reads `to_world`, the film and sampler children and the medium.
    explicit Sensor(const Properties& props);

    Transform to_world_;
    std::shared_ptr<Film> film_;
    std::shared_ptr<Sampler> sampler_;
    std::shared_ptr<Medium> medium_;
};

}  // namespace femto
