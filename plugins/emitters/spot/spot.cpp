// spot: a spot light (Mitsuba's `spot`), shining along local +z of `to_world` from
// to_world(0, 0, 0).
//
// Radiant intensity I in directions within `beam_width` of the axis, falling off linearly in
// angle to 0 at `cutoff_angle`, Mitsuba's falloff curve:
//     f(theta) = 1                                          theta <= beam_width
//              = (cutoff - theta) / (cutoff - beam_width)   beam_width < theta < cutoff
//              = 0                                          theta >= cutoff
// The weight of a sample is I f(theta) / d^2 (a delta emitter with pdf 1).
#include <cmath>
#include <string>

#include "femto/emitter.h"
#include "femto/log.h"
#include "femto/plugin.h"
#include "femto/warp.h"

namespace femto {
namespace {

class SpotEmitter final : public Emitter {
public:
    explicit SpotEmitter(const Properties& props)
        : Emitter(props), intensity_(read_emission(props, "intensity", Color(1.f))) {
        const double cutoff_deg = props.get_float("cutoff_angle", 20.0);
        if (!(cutoff_deg > 0 && cutoff_deg <= 180))
            props.fail("cutoff_angle", "cutoff_angle must be in (0, 180] degrees, but " +
                                           std::to_string(cutoff_deg) + " was given");
        // The default is a formula, "3/4 cutoff_angle" in the schema.
        double beam_deg =
            props.has("beam_width") ? props.get_float("beam_width") : cutoff_deg * 0.75;
        if (!(beam_deg >= 0))
            props.fail("beam_width", "beam_width must be in [0, cutoff_angle] degrees, but " +
                                         std::to_string(beam_deg) + " was given");
        if (beam_deg > cutoff_deg) {
            // Mitsuba clamps with a warning too: the scene still renders as its author saw it.
            log_warning(props.location_of("beam_width"),
                        "spot: beam_width (" + std::to_string(beam_deg) +
                            ") is larger than cutoff_angle (" + std::to_string(cutoff_deg) +
                            "); using beam_width = cutoff_angle");
            beam_deg = cutoff_deg;
        }
        cutoff_ = cutoff_deg * M_PI / 180.0;
        beam_ = beam_deg * M_PI / 180.0;
        cos_cutoff_ = static_cast<float>(std::cos(cutoff_));
        cos_beam_ = static_cast<float>(std::cos(beam_));

        const Transform to_world = read_to_world(props);
        position_ = to_world.point(Vec3(0.f));
        world_to_local_ = to_world.inverse();
        local_to_world_ = to_world;
    }

    /// Mitsuba's falloff for a unit direction in the light's local frame.
    float falloff(const Vec3& local_dir) const {
        const float cos_theta = local_dir.z;
        if (!(cos_theta > cos_cutoff_)) return 0.f;
        if (cos_theta >= cos_beam_) return 1.f;
        const double theta = std::acos(std::min(1.0, static_cast<double>(cos_theta)));
        return static_cast<float>(clamp((cutoff_ - theta) / (cutoff_ - beam_), 0.0, 1.0));
    }

    EmitterSample sample_direct(const Vec3& ref, Vec2 /*u*/) const override {
        EmitterSample es;
        const Vec3 d = position_ - ref;
        const float dist2 = squared_length(d);
        if (!(dist2 > 0) || !std::isfinite(dist2)) return es;
        const Vec3 local = world_to_local_.vector(-d);
        const float local_len = length(local);
        if (!(local_len > 0)) return es;
        const float f = falloff(local / local_len);
        if (!(f > 0)) return es;
        const float dist = std::sqrt(dist2);
        es.p = position_;
        es.n = Vec3();
        es.wi = d / dist;
        es.distance = dist;
        es.pdf = 1.f;
        es.weight = intensity_ * (f / dist2);
        es.delta = true;
        return es;
    }

    bool is_delta() const override { return true; }

    // A direction uniform in the cone of cutoff_angle (where the falloff is not zero).
    EmissionSample sample_emission(Vec2, Vec2 u_direction) const override {
        EmissionSample es;
        const Vec3 local = warp::square_to_uniform_cone(u_direction, cos_cutoff_);
        const float pdf = warp::uniform_cone_pdf(local, cos_cutoff_);
        const Vec3 d = local_to_world_.vector(local);
        if (!(pdf > 0) || !(length(d) > 0)) return es;
        es.p = position_;
        es.d = normalize(d);
        es.pdf_position = 1.f;
        es.pdf_direction = pdf;
        es.weight = intensity_ * (falloff(local) / pdf);
        es.delta_position = true;
        return es;
    }
    Color eval_direction(const EmissionSample&, const Vec3& d) const override {
        const Vec3 local = world_to_local_.vector(d);
        const float len = length(local);
        return len > 0 ? intensity_ * falloff(local / len) : Color();
    }
    void pdf_emission(const EmissionSample&, const Vec3& d, float& pdf_position,
                      float& pdf_direction) const override {
        const Vec3 local = world_to_local_.vector(d);
        const float len = length(local);
        pdf_position = 1.f;
        pdf_direction = len > 0 ? warp::uniform_cone_pdf(local / len, cos_cutoff_) : 0.f;
    }

private:
    Color intensity_;
    double cutoff_ = 0, beam_ = 0;
    float cos_cutoff_ = 0, cos_beam_ = 0;
    Vec3 position_;
    Transform world_to_local_, local_to_world_;
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::SpotEmitter, femto::PluginKind::Emitter, "spot",
             "Spot light along local +z with Mitsuba's linear angular falloff",
             {{"intensity", "color", "1", "radiant intensity on the axis (W/sr per channel)"},
              {"cutoff_angle", "float", "20", "angle (degrees) beyond which no light is emitted"},
              {"beam_width", "float", "3/4 cutoff_angle",
               "angle (degrees) within which the full intensity is emitted"},
              {"to_world", "transform", "identity",
               "light frame: at to_world(0, 0, 0), shining along local +z"}})
