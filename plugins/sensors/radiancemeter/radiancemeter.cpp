// radiancemeter (Mitsuba 3): measures the radiance arriving along one ray, the limit of a
// pinhole camera whose field of view shrinks to zero. Its film has one pixel; every camera
// sample traces the same ray, so with a transient film the pixel is the radiance's time profile
// along that ray. A connection from a light path never lands on a single ray (a set of measure
// zero), so light tracers refuse this sensor and BDPT uses its camera strategies only.
#include <cmath>
#include <string>

#include "femto/plugin.h"
#include "femto/sensor.h"

namespace {

using namespace femto;

class RadianceMeter final : public Sensor {
public:
    explicit RadianceMeter(const Properties& props) : Sensor(props) {
        if (film_->width() != 1 || film_->height() != 1)
            props.fail("film",
                       "radiancemeter measures one ray: its film must be 1 x 1 pixels, not " +
                           std::to_string(film_->width()) + " x " +
                           std::to_string(film_->height()));
        Vec3 origin, direction;
        if (props.has("to_world")) {
            // Mitsuba 3: to_world wins over origin / direction; they are then ignored.
            if (props.has("origin")) props.get_point("origin");
            if (props.has("direction")) props.get_vector("direction");
            origin = to_world_.point(Vec3(0.f));
            direction = to_world_.vector({0, 0, 1});
        } else {
            if (props.has("origin") != props.has("direction"))
                props.fail(props.has("origin") ? "origin" : "direction",
                           "give both origin and direction (or a to_world)");
            origin = props.get_point("origin", Vec3(0.f));
            direction = props.get_vector("direction", Vec3(0, 0, 1));
        }
        const float len = length(direction);
        if (!(len > 0) || !std::isfinite(len))
            props.fail(props.has("direction") ? "direction" : "to_world",
                       "the measured direction has zero length");
        if (!within_scene_range(origin))
            props.fail(props.has("origin") ? "origin" : "to_world",
                       outside_scene_range("the radiance meter", origin));
        origin_ = origin;
        direction_ = direction / len;
    }

    Ray sample_ray(Vec2, Vec2) const override { return Ray{origin_, direction_, 0.f, kInfinity}; }

private:
    Vec3 origin_, direction_;
};

}  // namespace

FEMTO_PLUGIN(RadianceMeter, femto::PluginKind::Sensor, "radiancemeter",
             "Radiance along one ray (Mitsuba 3); needs a 1 x 1 film",
             {{"origin", "point", "0, 0, 0",
               "where the ray starts (with direction; to_world takes precedence)"},
              {"direction", "vector", "0, 0, 1", "direction the meter looks in (with origin)"}})
