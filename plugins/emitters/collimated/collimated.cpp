// collimated: a laser beam along local +z of `to_world`, from the plane through
// to_world(0, 0, 0) perpendicular to the beam.
//
// Without a `radius` it is Mitsuba 0.6's `collimated`: an ideal beam of zero width, a single
// ray from to_world(0, 0, 0) carrying `power` (default 1), a delta in both position and
// direction. Light paths start from it (light tracing, BDPT, photon methods); nothing can
// connect to it or hit it, so a path tracer never sees its light, as in Mitsuba.
//
// With a `radius` (scene units, > 0) the beam is a cylinder of parallel light that a path
// tracer can see: inside it the light arrives from -beam direction with irradiance E (on a
// surface perpendicular to the beam), outside there is none. E is `irradiance`, or `power` /
// (pi radius^2). Light starts at the origin plane, so the path length of the light to a point
// is its axial distance from that plane (what transient rendering measures).
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
        if (props.has("irradiance") && props.has("power"))
            props.fail("power", "give either irradiance or power, not both");
        if (props.has("radius"))
            read_finite_beam(props);
        else
            read_thin_beam(props);
        const Transform to_world = read_to_world(props);
        origin_ = to_world.point(Vec3(0.f));
        const Vec3 dir = to_world.vector({0, 0, 1});
        if (!(length(dir) > 0) || !is_finite(dir))
            props.fail("to_world", "to_world maps the beam direction (local +z) to zero");
        dir_ = normalize(dir);
    }

    EmitterSample sample_direct(const Vec3& ref, Vec2 /*u*/) const override {
        EmitterSample es;
        if (thin()) return es;  // a single ray lights no point with nonzero probability
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

    // The thin beam: its one ray, carrying the power (a delta in position and direction, as
    // Mitsuba 0.6 samples it). The finite beam: a uniform point on its disk at the origin
    // plane, leaving along the beam.
    EmissionSample sample_emission(Vec2 u_position, Vec2) const override {
        EmissionSample es;
        es.d = dir_;
        es.pdf_direction = 1.f;
        es.delta_direction = true;
        if (thin()) {
            es.p = origin_;
            es.pdf_position = 1.f;
            es.weight = power_;
            es.delta_position = true;
            return es;
        }
        const Vec2 disk = warp::square_to_uniform_disk(u_position);
        es.p = origin_ + Frame(dir_).to_world(Vec3(disk.x * radius_, disk.y * radius_, 0.f));
        es.n = dir_;
        es.pdf_position = float(1.0 / (M_PI * double(radius_) * radius_));
        es.weight = irradiance_ * float(M_PI * double(radius_) * radius_);  // the beam's power
        return es;
    }
    void pdf_emission(const EmissionSample&, const Vec3&, float& pdf_position,
                      float& pdf_direction) const override {
        pdf_position = thin() ? 1.f : float(1.0 / (M_PI * double(radius_) * radius_));
        pdf_direction = 1.f;
    }

private:
    bool thin() const { return radius_ == 0.f; }

    void read_thin_beam(const Properties& props) {
        if (props.has("irradiance"))
            props.fail("irradiance",
                       "a beam without a radius is infinitely thin: give its \"power\" (or a "
                       "\"radius\" for a beam of this irradiance)");
        power_ = read_emission(props, "power", Color(1.f));
        if (!power_.is_finite()) props.fail("power", "the power of the beam is not finite");
    }

    void read_finite_beam(const Properties& props) {
        const double radius = props.get_float("radius");
        if (!(radius > 0) || !std::isfinite(radius))
            props.fail("radius", "the beam radius must be > 0 and finite (in scene units), but " +
                                     std::to_string(radius) +
                                     " was given; leave it out for an infinitely thin beam");
        radius_ = static_cast<float>(radius);
        if (props.has("power"))
            irradiance_ = read_emission(props, "power", Color(1.f)) /
                          static_cast<float>(M_PI * radius * radius);
        else
            irradiance_ = read_emission(props, "irradiance", Color(1.f));
        if (!irradiance_.is_finite())
            props.fail(props.has("power") ? "power" : "irradiance",
                       "the irradiance of the beam is not finite");
    }

    Color irradiance_;  // the finite beam's
    Color power_;       // the thin beam's
    float radius_ = 0;  // 0: the thin beam
    Vec3 origin_, dir_;
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::CollimatedEmitter, femto::PluginKind::Emitter, "collimated",
             "Collimated beam (laser) along local +z: infinitely thin (Mitsuba 0.6), or of a "
             "given radius",
             {{"radius", "float", "",
               "beam radius in scene units (> 0); none: an infinitely thin beam (a single ray, "
               "seen only by light paths)"},
              {"irradiance", "color", "1",
               "irradiance inside a beam with a radius, on a surface perpendicular to it "
               "(W/m^2)"},
              {"power", "color", "",
               "beam power (W; 1 for a thin beam); with a radius, irradiance = power / (pi "
               "radius^2)"},
              {"to_world", "transform", "identity",
               "beam frame: starts at to_world(0, 0, 0), points along local +z"}})
