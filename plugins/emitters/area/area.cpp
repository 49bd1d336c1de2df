// area: a diffuse area light on the shape that holds it (Mitsuba's `area`).
//
// Uniform radiance leaves the front side of the surface only: the side the geometric normal
// points to (the host has already flipped hit.ng and ShapeSample::n for flip_normals).
// Points are sampled by the shape's own direct-lighting strategy (area sampling converted
// to solid angle, or the visible cone for spheres), so pdf_direct() is the shape's pdf too.
#include <algorithm>
#include <cmath>

#include "femto/emitter.h"
#include "femto/plugin.h"
#include "femto/warp.h"

namespace femto {
namespace {

class AreaEmitter final : public Emitter {
public:
    explicit AreaEmitter(const Properties& props)
        : Emitter(props), radiance_(read_emission(props, "radiance", Color(1.f))) {}

    EmitterSample sample_direct(const Vec3& ref, Vec2 u) const override {
        EmitterSample es;
        if (!shape_) return es;
        const ShapeSample ss = shape_->sample_direct(ref, u);
        if (!(ss.pdf > 0) || !std::isfinite(ss.pdf)) return es;
        // The back side emits nothing: the sampled point must face the reference point.
        if (!(dot(ss.wi, ss.n) < 0)) return es;
        es.p = ss.p;
        es.n = ss.n;
        es.wi = ss.wi;
        es.distance = ss.distance;
        es.pdf = ss.pdf;
        es.weight = radiance_ / ss.pdf;
        es.delta = false;
        return es;
    }

    float pdf_direct(const Vec3& ref, const Hit& hit) const override {
        if (!shape_ || !(dot(ref - hit.p, hit.ng) > 0)) return 0.f;
        return shape_->pdf_direct(ref, hit);
    }

    Color eval(const Hit& hit, const Vec3& w) const override {
        return dot(w, hit.ng) > 0 ? radiance_ : Color();
    }

    bool is_delta() const override { return false; }

    // A uniform point on the shape, a cosine-weighted direction about its normal.
    EmissionSample sample_emission(Vec2 u_position, Vec2 u_direction) const override {
        EmissionSample es;
        if (!shape_) return es;
        const ShapeSample ss = shape_->sample_area(u_position);
        if (!(ss.pdf > 0) || !std::isfinite(ss.pdf)) return es;
        const Vec3 local = warp::square_to_cosine_hemisphere(u_direction);
        const float pdf_dir = warp::cosine_hemisphere_pdf(local);
        if (!(pdf_dir > 0)) return es;
        es.p = ss.p;
        es.n = ss.n;
        es.p_error = ss.p_error;
        es.d = Frame(ss.n).to_world(local);
        es.pdf_position = ss.pdf;
        es.pdf_direction = pdf_dir;
        es.weight = radiance_ * float(M_PI / double(ss.pdf));  // L cos / (pdf_pos cos / pi)
        return es;
    }
    Color eval_direction(const EmissionSample& at, const Vec3& d) const override {
        const float c = dot(d, at.n);
        return c > 0 ? radiance_ * c : Color();
    }
    void pdf_emission(const EmissionSample& at, const Vec3& d, float& pdf_position,
                      float& pdf_direction) const override {
        pdf_position = shape_ ? 1.f / shape_->surface_area() : 0.f;
        pdf_direction = std::max(0.f, dot(d, at.n)) * float(kInvPi);
    }

private:
    Color radiance_;
};

}  // namespace
}  // namespace femto

FEMTO_PLUGIN(femto::AreaEmitter, femto::PluginKind::Emitter, "area",
             "Diffuse area light: uniform radiance from the front side of its shape",
             {{"radiance", "color", "1", "emitted radiance (W / (m^2 sr) per channel)"}})
