// Orthographic camera (Mitsuba conventions): the local square x in [-1, 1] spans the film's
// width (y in [-1/aspect, 1/aspect] its height); scale `to_world` to set the visible extent.
#include "femto/plugin.h"
#include "femto/sensor.h"

namespace {

using namespace femto;

class Orthographic final : public Sensor {
public:
    explicit Orthographic(const Properties& props) : Sensor(props) {
        near_ = props.get_float("near_clip", 0.01);
        far_ = props.get_float("far_clip", 10000.0);
        if (!(near_ >= 0) || !(far_ > near_))
            props.fail("near_clip", "need 0 <= near_clip < far_clip");
        // Read by Mitsuba's projective cameras for depth of field, which this camera has not.
        if (props.has("focus_distance")) props.get_float("focus_distance");
        inv_aspect_ = float(film_->height()) / float(film_->width());
        // Rays start anywhere on the film's rectangle: its corners must be in range too.
        for (const float x : {-1.f, 1.f})
            for (const float y : {-inv_aspect_, inv_aspect_})
                if (const Vec3 c = to_world_.point({x, y, 0.f}); !within_scene_range(c))
                    props.fail("to_world", outside_scene_range("a corner of the view", c));
        const Vec3 d = to_world_.vector({0, 0, 1});
        dir_len_ = length(d);
        dir_ = d / dir_len_;
    }

    Ray sample_ray(Vec2 pos, Vec2) const override {
        const float nx = pos.x / float(film_->width()), ny = pos.y / float(film_->height());
        const Vec3 o = to_world_.point({1 - 2 * nx, (1 - 2 * ny) * inv_aspect_, 0.f});
        return Ray{o, dir_, float(near_) * dir_len_, float(far_) * dir_len_};
    }

    bool sample_differential(Vec2 pos, Vec2 aperture, RayDifferential& out) const override {
        const Ray x = sample_ray({pos.x + 1.f, pos.y}, aperture);
        const Ray y = sample_ray({pos.x, pos.y + 1.f}, aperture);
        out = {x.o, x.d, y.o, y.d};
        return true;
    }

private:
    double near_ = 0, far_ = 0;
    float inv_aspect_ = 1, dir_len_ = 1;
    Vec3 dir_;
};

}  // namespace

FEMTO_PLUGIN(Orthographic, femto::PluginKind::Sensor, "orthographic",
             "Orthographic camera; to_world's scale sets the visible extent",
             {{"near_clip", "float", "0.01", "near clipping distance"},
              {"far_clip", "float", "10000", "far clipping distance"},
              {"focus_distance", "float", "",
               "accepted for Mitsuba compatibility; no effect (no depth of field)"}})
