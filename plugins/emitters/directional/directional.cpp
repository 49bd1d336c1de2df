// directional: a distant light whose parallel rays all travel along one direction (the sun as
// Mitsuba models it, `directional` in Mitsuba 0.6 and 3). A surface facing the light receives
// the irradiance E; no ray can hit the light (it is a delta in direction).
//
// Time (docs/distant-light.md): the light is a plane wave that crosses the plane tangent to the
// scene's sphere on the side it comes from (SceneSphere) at its emission time, so a point x
// receives it after the optical length radius - dot(x - center, -direction). Light paths
// start on the disk of the sphere's radius in that plane, like a collimated beam as wide as
// the scene (`collimated` with radius = the scene's radius, power E pi r^2).
#include <cmath>

#include "femto/emitter.h"
#include "femto/plugin.h"
#include "femto/warp.h"

namespace femto {
namespace {

class DirectionalEmitter final : public Emitter {
public:
    explicit DirectionalEmitter(const Properties& props) : Emitter(props) {
        irradiance_ = read_emission(props, "irradiance", Color(1.f));
        if (props.has("direction") && props.has("to_world"))
            props.fail("direction",
                       "give the light's direction either as \"direction\" or as \"to_world\" "
                       "(its local +z), not both");
        const Vec3 d = props.has("to_world") ? read_to_world(props).vector({0, 0, 1})
                                             : props.get_vector("direction", Vec3(0, 0, 1));
        if (!(length(d) > 0) || !is_finite(d))
            props.fail(props.has("direction") ? "direction" : "to_world",
                       "the light's direction must be a finite, non-zero vector");
        travel_ = normalize(d);
    }

    bool is_delta() const override { return true; }
    bool is_infinite() const override { return true; }
    void set_scene_sphere(const SceneSphere& sphere) override { sphere_ = sphere; }

    // The light reaches every point from -direction, starting on its plane wave's start plane.
    EmitterSample sample_direct(const Vec3& ref, Vec2 /*u*/) const override {
        EmitterSample es;
        es.wi = -travel_;
        es.p = sphere_.plane_wave_start(ref, es.wi);
        es.n = travel_;
        es.distance = float(sphere_.plane_wave_distance(ref, es.wi));
        es.pdf = 1.f;
        es.weight = irradiance_;
        es.delta = true;
        return es;
    }

    // A uniform point on the disk that covers the scene, leaving along the light's direction.
    EmissionSample sample_emission(Vec2 u_position, Vec2) const override {
        EmissionSample es;
        es.p = sphere_.plane_wave_disk(-travel_, warp::square_to_uniform_disk(u_position));
        es.n = travel_;
        es.d = travel_;
        es.pdf_position = sphere_.disk_pdf();
        es.pdf_direction = 1.f;
        es.weight = irradiance_ / es.pdf_position;  // the power through the disk
        es.delta_direction = true;
        return es;
    }
    void pdf_emission(const EmissionSample&, const Vec3&, float& pdf_position,
                      float& pdf_direction) const override {
        pdf_position = sphere_.disk_pdf();
        pdf_direction = 1.f;
    }

private:
    Color irradiance_;
    Vec3 travel_;  // the direction the light travels in
    SceneSphere sphere_;
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::DirectionalEmitter, femto::PluginKind::Emitter, "directional",
             "Distant light from one direction (parallel rays, e.g. the sun)",
             {{"irradiance", "color", "1",
               "irradiance on a surface perpendicular to the light (W/m^2 per channel)"},
              {"direction", "vector", "(0, 0, 1)",
               "the direction the light travels in (alternative to to_world)"},
              {"to_world", "transform", "",
               "the light travels along to_world's local +z (alternative to direction)"}})
