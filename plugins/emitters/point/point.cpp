// point: an isotropic point light (Mitsuba's `point`).
//
// Placed by `position` or by `to_world` (at to_world(0, 0, 0)), not both. Radiant intensity
// I (W/sr) gives the irradiance I / d^2 at distance d (normal incidence; the integrator
// applies the cosine), returned as the weight of a delta sample with pdf 1.
#include <cmath>

#include "femto/emitter.h"
#include "femto/plugin.h"
#include "femto/warp.h"

namespace femto {
namespace {

class PointEmitter final : public Emitter {
public:
    explicit PointEmitter(const Properties& props)
        : Emitter(props), intensity_(read_emission(props, "intensity", Color(1.f))) {
        if (props.has("position") && props.has("to_world"))
            props.fail("position", "give either position or to_world, not both");
        position_ = props.has("to_world") ? read_to_world(props).point(Vec3(0.f))
                                          : props.get_point("position", Vec3(0.f));
        if (!within_scene_range(position_))
            props.fail("position", outside_scene_range("the point light", position_));
    }

    EmitterSample sample_direct(const Vec3& ref, Vec2 /*u*/) const override {
        EmitterSample es;
        const Vec3 d = position_ - ref;
        const float dist2 = squared_length(d);
        if (!(dist2 > 0) || !std::isfinite(dist2)) return es;
        const float dist = std::sqrt(dist2);
        es.p = position_;
        es.n = Vec3();
        es.wi = d / dist;
        es.distance = dist;
        es.pdf = 1.f;
        es.weight = intensity_ / dist2;
        es.delta = true;
        return es;
    }

    bool is_delta() const override { return true; }

    EmissionSample sample_emission(Vec2, Vec2 u_direction) const override {
        EmissionSample es;
        es.p = position_;
        es.d = warp::square_to_uniform_sphere(u_direction);
        es.pdf_position = 1.f;
        es.pdf_direction = warp::uniform_sphere_pdf();
        es.weight = intensity_ * float(4 * M_PI);
        es.delta_position = true;
        return es;
    }
    Color eval_direction(const EmissionSample&, const Vec3&) const override { return intensity_; }
    void pdf_emission(const EmissionSample&, const Vec3&, float& pdf_position,
                      float& pdf_direction) const override {
        pdf_position = 1.f;
        pdf_direction = warp::uniform_sphere_pdf();
    }

private:
    Color intensity_;
    Vec3 position_;
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::PointEmitter, femto::PluginKind::Emitter, "point", "Isotropic point light",
             {{"intensity", "color", "1", "radiant intensity (W/sr per channel)"},
              {"position", "point", "(0, 0, 0)", "location (alternative to to_world)"},
              {"to_world", "transform", "",
               "places the light at to_world(0, 0, 0) (alternative to position)"}})
