// spherical (Mitsuba 0.6): a 360-degree latitude-longitude camera at one point. Film x covers
// the azimuth phi in [0, 2 pi), film y the polar angle theta in [0, pi) from local +y (up);
// local direction (sin phi sin theta, cos theta, -cos phi sin theta), as Mitsuba's: the top row
// looks up, the image's left edge along -z and its centre along +z.
//
// A pixel's value is the radiance averaged over the pixel's (phi, theta) rectangle. Film
// positions are drawn uniformly, so a direction's density is 1 / (2 pi^2 sin theta): fluence
// is the sum over pixels of value x 2 pi^2 sin theta / pixels (exactly, per sample). The camera
// is a point, so light paths connect to it (light tracing, BDPT's strategies t = 1).
#include <algorithm>
#include <cmath>

#include "femto/plugin.h"
#include "femto/sensor.h"

namespace {

using namespace femto;

class Spherical final : public Sensor {
public:
    explicit Spherical(const Properties& props) : Sensor(props) {
        // Mitsuba refuses scale too: the directions would not be unit and the film's solid
        // angles would not be the sphere's (nor with a shear).
        const Vec3 ax = to_world_.vector({1, 0, 0}), ay = to_world_.vector({0, 1, 0}),
                   az = to_world_.vector({0, 0, 1});
        const bool rigid = std::abs(length(ax) - 1.f) < 1e-4f &&
                           std::abs(length(ay) - 1.f) < 1e-4f &&
                           std::abs(length(az) - 1.f) < 1e-4f && std::abs(dot(ax, ay)) < 1e-4f &&
                           std::abs(dot(ay, az)) < 1e-4f && std::abs(dot(az, ax)) < 1e-4f;
        if (!rigid)
            props.fail("to_world",
                       "the spherical camera's to_world must not scale or shear (use "
                       "translate, rotate and lookat)");
        origin_ = to_world_.point(Vec3(0.f));
        if (!within_scene_range(origin_))
            props.fail("to_world", outside_scene_range("the spherical camera", origin_));
        to_local_ = to_world_.inverse();
        near_ = props.get_float("near_clip", 0.0);
        far_ = props.get_float("far_clip", 1e30);
        if (!(near_ >= 0) || !(far_ > near_))
            props.fail("near_clip", "need 0 <= near_clip < far_clip");
    }

    Ray sample_ray(Vec2 pos, Vec2) const override {
        const double phi = 2 * M_PI * pos.x / film_->width();
        const double theta = M_PI * pos.y / film_->height();
        const Vec3 local{float(std::sin(phi) * std::sin(theta)), float(std::cos(theta)),
                         float(-std::cos(phi) * std::sin(theta))};
        return Ray{origin_, normalize(to_world_.vector(local)), float(near_),
                   float(std::min(far_, double(kInfinity)))};
    }

    bool connectable() const override { return true; }

    float pdf_direction(const Vec3& d) const override {
        Vec2 pos;
        const double sin_theta = film_position(d, pos);
        return sin_theta > 0 ? float(1.0 / (2 * M_PI * M_PI * sin_theta)) : 0.f;
    }

    SensorSample sample_direct(const Vec3& ref, Vec2) const override {
        SensorSample s;
        const Vec3 v = origin_ - ref;
        const double dist = distance_between(ref, origin_);
        if (!(dist > near_ && dist <= far_)) return s;
        s.wi = v / float(dist);
        const double sin_theta = film_position(-s.wi, s.pos);
        if (!(sin_theta > 0)) return s;
        s.p = origin_;
        s.distance = dist;
        s.weight = float(1.0 / (2 * M_PI * M_PI * sin_theta * dist * dist));
        return s;
    }

private:
    // Film position (pixels) of the camera ray leaving in world direction d (unit); returns
    // sin(theta), 0 at the poles, where the density is unbounded and no connection is made.
    double film_position(const Vec3& d, Vec2& pos) const {
        const Vec3 l = to_local_.vector(d);
        const double y = std::clamp(double(l.y), -1.0, 1.0);
        const double sin_theta = std::sqrt(std::max(0.0, 1 - y * y));
        if (!(sin_theta > 1e-7)) return 0;
        double phi = std::atan2(double(l.x), -double(l.z));
        if (phi < 0) phi += 2 * M_PI;
        pos = Vec2{float(std::min(phi / (2 * M_PI), 0x1.fffffep-1) * film_->width()),
                   float(std::min(std::acos(y) / M_PI, 0x1.fffffep-1) * film_->height())};
        return sin_theta;
    }

    Vec3 origin_;
    Transform to_local_;
    double near_ = 0, far_ = 0;
};

}  // namespace

FEMTO_PLUGIN(Spherical, femto::PluginKind::Sensor, "spherical",
             "360-degree latitude-longitude camera (Mitsuba 0.6)",
             {{"near_clip", "float", "0", "rays start this far from the camera"},
              {"far_clip", "float", "1e30", "rays end this far from the camera"}})
