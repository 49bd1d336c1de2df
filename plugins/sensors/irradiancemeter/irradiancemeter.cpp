// irradiancemeter (Mitsuba 3): the irradiance on the front side of the shape it is nested in
// (the side the normal points to), averaged over the shape's area:
//     E = (1 / A) * integral over the shape of integral over the hemisphere of L cos(theta).
// Its film has one pixel. Camera rays start at a uniform point of the shape (pdf 1 / A) in a
// cosine-distributed direction (pdf cos / pi), so each ray's radiance times pi estimates E
// (ray_weight()). Light paths connect to a uniform point of the shape: a splat of the light
// arriving there times cos / distance^2 estimates the same E, which makes the irradiance of
// point and spot lights (never hit by camera rays) measurable with transient_light.
//
// The point on the shape is the film position of the camera sample (its one pixel is the unit
// square), so the film's reconstruction filter must weigh every position alike: a box.
// Another filter would weigh the shape's centre more than its rim (Mitsuba 3 warns and renders
// that weighted average; femto refuses it).
//
// Time: camera paths start on the shape, so a transient film records when light reaches it.
// The meter sits in the shape's exterior medium unless it names a medium of its own.
#include <cmath>
#include <string>

#include "femto/plugin.h"
#include "femto/sensor.h"
#include "femto/shape.h"
#include "femto/warp.h"

namespace {

using namespace femto;

class IrradianceMeter final : public Sensor {
public:
    explicit IrradianceMeter(const Properties& props) : Sensor(props) {
        if (props.has("to_world"))
            props.fail("to_world",
                       "irradiancemeter takes its place from the shape it is nested in; give "
                       "the shape the to_world");
        if (film_->width() != 1 || film_->height() != 1)
            props.fail("film",
                       "irradiancemeter measures one value: its film must be 1 x 1 "
                       "pixels, not " +
                           std::to_string(film_->width()) + " x " +
                           std::to_string(film_->height()));
        if (film_->rfilter().radius() > 0.5f + 1e-6f)
            props.fail("film",
                       "irradiancemeter needs a box reconstruction filter (<rfilter "
                       "type=\"box\"/> in its film): the film position of each sample picks the "
                       "point on the shape, and a wider filter would weigh the shape's centre "
                       "more than its rim");
    }

    bool needs_shape() const override { return true; }
    void attach(const Shape& shape) override {
        shape_ = &shape;
        if (!medium_) medium_ = shape.exterior_ptr();
    }

    Ray sample_ray(Vec2 pos, Vec2 aperture) const override {
        if (!shape_) throw SceneError(location(), "irradiancemeter used without its shape");
        // The film has one pixel, so the film position is a uniform point of the unit square.
        const ShapeSample ss =
            shape_->sample_area({pos.x - std::floor(pos.x), pos.y - std::floor(pos.y)});
        const Vec3 d = Frame(ss.n).to_world(warp::square_to_cosine_hemisphere(aperture));
        return Ray{offset_origin(ss.p, ss.n, d, ss.p_error), d, 0.f, kInfinity};
    }
    float ray_weight() const override { return float(M_PI); }

    bool connectable() const override { return true; }
    bool has_area() const override { return true; }

    SensorSample sample_direct(const Vec3& ref, Vec2 u) const override {
        SensorSample s;
        if (!shape_) throw SceneError(location(), "irradiancemeter used without its shape");
        const ShapeSample ss = shape_->sample_area(u);
        const double dist = distance_between(ref, ss.p);
        if (!(dist > 0)) return s;
        s.wi = (ss.p - ref) / float(dist);
        const float cos_sensor = -dot(s.wi, ss.n);
        if (!(cos_sensor > 0)) return s;  // the back side measures nothing
        s.p = ss.p;
        s.distance = dist;
        s.pos = Vec2{0.5f, 0.5f};
        // W = 1 / A and the point's density 1 / A cancel; the box filter weighs the splat 1.
        s.weight = float(double(cos_sensor) / (dist * dist));
        return s;
    }

private:
    const Shape* shape_ = nullptr;
};

}  // namespace

FEMTO_PLUGIN(IrradianceMeter, femto::PluginKind::Sensor, "irradiancemeter",
             "Irradiance on the shape it is nested in, averaged over its area (Mitsuba 3); "
             "needs a 1 x 1 film",
             {})
