// constant: light of the same radiance from every direction, from outside the scene (Mitsuba's
// `constant` environment, 0.6 and 3). Every ray that leaves the scene sees `radiance`; light
// samples pick directions uniformly on the sphere, as Mitsuba 3 does.
//
// Time (docs/distant-light.md): the light from each direction is a plane wave that crosses the
// plane tangent to the scene's sphere on the side it comes from (SceneSphere) at its emission
// time. Light paths start on the disk of the sphere's radius in that plane.
#include "femto/emitter.h"
#include "femto/plugin.h"
#include "femto/warp.h"

namespace femto {
namespace {

class ConstantEmitter final : public Emitter {
public:
    explicit ConstantEmitter(const Properties& props) : Emitter(props) {
        radiance_ = read_emission(props, "radiance", Color(1.f));
    }

    bool is_delta() const override { return false; }
    bool is_infinite() const override { return true; }
    void set_scene_sphere(const SceneSphere& sphere) override { sphere_ = sphere; }
    Color eval_environment(const Vec3&) const override { return radiance_; }
    float pdf_environment(const Vec3&) const override { return warp::uniform_sphere_pdf(); }

    EmitterSample sample_direct(const Vec3& ref, Vec2 u) const override {
        EmitterSample es;
        es.wi = warp::square_to_uniform_sphere(u);
        es.p = sphere_.plane_wave_start(ref, es.wi);
        es.n = -es.wi;
        es.distance = float(sphere_.plane_wave_distance(ref, es.wi));
        es.pdf = warp::uniform_sphere_pdf();
        es.weight = radiance_ / es.pdf;
        return es;
    }

    // A direction the light comes from, then a point of the disk across the scene it crosses.
    EmissionSample sample_emission(Vec2 u_position, Vec2 u_direction) const override {
        EmissionSample es;
        const Vec3 wi = warp::square_to_uniform_sphere(u_direction);
        es.p = sphere_.plane_wave_disk(wi, warp::square_to_uniform_disk(u_position));
        es.n = -wi;
        es.d = -wi;
        es.pdf_position = sphere_.disk_pdf();
        es.pdf_direction = warp::uniform_sphere_pdf();
        es.weight = radiance_ / (es.pdf_position * es.pdf_direction);
        return es;
    }
    // The disk point sees no light but its own direction's: a connection from it to the camera
    // carries nothing (rays leaving the scene see the environment instead).
    void pdf_emission(const EmissionSample&, const Vec3&, float& pdf_position,
                      float& pdf_direction) const override {
        pdf_position = sphere_.disk_pdf();
        pdf_direction = warp::uniform_sphere_pdf();
    }

private:
    Color radiance_;
    SceneSphere sphere_;
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::ConstantEmitter, femto::PluginKind::Emitter, "constant",
             "Constant environment: the same radiance from every direction",
             {{"radiance", "color", "1", "radiance from every direction (W/(m^2 sr) per channel)"}})
