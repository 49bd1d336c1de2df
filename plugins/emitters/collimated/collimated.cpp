// collimated: a laser beam, a cylinder of parallel light along local +z of `to_world`,
// starting at the plane through to_world(0, 0, 0) perpendicular to the beam.
//
// Mitsuba 0.6's `collimated` is infinitely thin, which a path tracer cannot see: a beam of
// zero cross-section is hit with probability zero and lights a set of zero area. So the
// beam here has a `radius` (scene units, required): inside the cylinder the light arrives
// from -beam direction with irradiance E (on a surface perpendicular to the beam), outside
// there is none. Light starts at the origin plane, so the path length of the light to a
// point is its axial distance from that plane (what transient rendering measures).
// E is `irradiance`, or `power` / (pi radius^2).
#include <cmath>
#include <string>

#include "femto/emitter.h"
#include "femto/plugin.h"
#include "femto/warp.h"

namespace femto {
namespace {

class CollimatedEmitter final : public Emitter {
public:
    explicit CollimatedEmitter(const Properties& props) : Emitter(props) {
        if (!props.has("radius"))
            props.fail("radius",
                       "the collimated emitter needs a beam \"radius\" (> 0, in scene units): an "
                       "infinitesimally thin beam cannot be seen by a path tracer");
        const double radius = props.get_float("radius");
        if (!(radius > 0))
            props.fail("radius", "the beam radius must be > 0 (in scene units), but " +
                                     std::to_string(radius) +
                                     " was given: an infinitesimally thin beam cannot be seen by "
                                     "a path tracer");
        radius_ = static_cast<float>(radius);
        if (props.has("irradiance") && props.has("power"))
            props.fail("power", "give either irradiance or power, not both");
        if (props.has("power"))
            irradiance_ = read_emission(props, "power", Color(1.f)) /
                          static_cast<float>(M_PI * radius * radius);
        else
            irradiance_ = read_emission(props, "irradiance", Color(1.f));
        if (!irradiance_.is_finite())
            props.fail(props.has("power") ? "power" : "irradiance",
                       "the irradiance of the beam is not finite");

        const Transform to_world = read_to_world(props);
        origin_ = to_world.point(Vec3(0.f));
        const Vec3 dir = to_world.vector({0, 0, 1});
        if (!(length(dir) > 0) || !is_finite(dir))
            props.fail("to_world", "to_world maps the beam direction (local +z) to zero");
        dir_ = normalize(dir);
    }

    EmitterSample sample_direct(const Vec3& ref, Vec2 /*u*/) const override {
        EmitterSample es;
        const Vec3 v = ref - origin_;
        const float axial = dot(v, dir_);
        if (!(axial > 0)) return es;  // behind the origin plane
        const Vec3 radial = v - dir_ * axial;
        if (!(squared_length(radial) <= radius_ * radius_)) return es;  // outside the beam
        es.p = ref - dir_ * axial;  // where this ray of the beam starts
        es.n = dir_;
        es.wi = -dir_;
        es.distance = axial;
        es.pdf = 1.f;
        es.weight = irradiance_;
        es.delta = true;
        return es;
    }

    bool is_delta() const override { return true; }

    // A uniform point on the beam's disk at its origin plane, leaving along the beam.
    EmissionSample sample_emission(Vec2 u_position, Vec2) const override {
        EmissionSample es;
        const Vec2 disk = warp::square_to_uniform_disk(u_position);
        es.p = origin_ + Frame(dir_).to_world(Vec3(disk.x * radius_, disk.y * radius_, 0.f));
        es.n = dir_;
        es.d = dir_;
        es.pdf_position = float(1.0 / (M_PI * double(radius_) * radius_));
        es.pdf_direction = 1.f;
        es.weight = irradiance_ * float(M_PI * double(radius_) * radius_);  // the beam's power
        es.delta_direction = true;
        return es;
    }
    void pdf_emission(const EmissionSample&, const Vec3&, float& pdf_position,
                      float& pdf_direction) const override {
        pdf_position = float(1.0 / (M_PI * double(radius_) * radius_));
        pdf_direction = 1.f;
    }

private:
    Color irradiance_;
    float radius_ = 0;
    Vec3 origin_, dir_;
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::CollimatedEmitter, femto::PluginKind::Emitter, "collimated",
             "Collimated beam (laser) of finite radius along local +z",
             {{"radius", "float", "", "beam radius in scene units (required, > 0)"},
              {"irradiance", "color", "1",
               "irradiance inside the beam on a surface perpendicular to it (W/m^2)"},
              {"power", "color", "", "beam power (W); irradiance = power / (pi radius^2)"},
              {"to_world", "transform", "identity",
               "beam frame: starts at to_world(0, 0, 0), points along local +z"}})
