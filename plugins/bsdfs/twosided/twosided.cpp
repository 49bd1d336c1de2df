// twosided: makes one-sided materials reflect on both sides (Mitsuba's `twosided`).
//
// Takes one or two nested <bsdf> children. The first is used when wi is on the front side
// (wi.z > 0). On the back side (wi.z < 0) the second child is used (the first when there is
// only one), evaluated in the mirrored frame: both directions have their z negated before
// the call, and a sampled direction has its z negated after it. wi.z == 0 scatters nothing.
// The children's vertex events (Bsdf::sample_vertex_event) are forwarded the same way.
#include <memory>
#include <string>
#include <vector>

#include "femto/bsdf.h"
#include "femto/plugin.h"

namespace {

using namespace femto;

Vec3 flip_z(const Vec3& v) { return {v.x, v.y, -v.z}; }

class TwoSided final : public Bsdf {
public:
    explicit TwoSided(const Properties& props) {
        const std::vector<ObjectPtr> children = props.objects(PluginKind::Bsdf);
        if (children.empty())
            props.fail("bsdf",
                       "twosided needs a nested <bsdf> (one for both sides, or two: "
                       "front then back)");
        if (children.size() > 2)
            props.fail("bsdf", "twosided takes at most two nested <bsdf> (front and back), but " +
                                   std::to_string(children.size()) + " were given");
        front_ = std::static_pointer_cast<Bsdf>(children[0]);
        back_ = children.size() == 2 ? std::static_pointer_cast<Bsdf>(children[1]) : front_;
        flags_ = front_->flags() | back_->flags();
    }

    uint32_t flags() const override { return flags_; }

    BsdfSample sample(const Hit& hit, const Vec3& wi, float u_lobe, Vec2 u) const override {
        if (wi.z > 0.f) return front_->sample(hit, wi, u_lobe, u);
        if (wi.z < 0.f) {
            BsdfSample s = back_->sample(hit, flip_z(wi), u_lobe, u);
            s.wo = flip_z(s.wo);
            return s;
        }
        return BsdfSample{};
    }

    Color eval(const Hit& hit, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z > 0.f) return front_->eval(hit, wi, wo);
        if (wi.z < 0.f) return back_->eval(hit, flip_z(wi), flip_z(wo));
        return Color(0.f);
    }

    float pdf(const Hit& hit, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z > 0.f) return front_->pdf(hit, wi, wo);
        if (wi.z < 0.f) return back_->pdf(hit, flip_z(wi), flip_z(wo));
        return 0.f;
    }

    bool reciprocal() const override { return front_->reciprocal() && back_->reciprocal(); }
    bool uses_footprint() const override {
        return front_->uses_footprint() || back_->uses_footprint();
    }
    bool uses_tangent() const override { return front_->uses_tangent() || back_->uses_tangent(); }
    bool adapts_sampling() const override {
        return front_->adapts_sampling() || back_->adapts_sampling();
    }
    float pixel_sample_share(const Hit& hit) const override {
        if (hit.wi.z >= 0.f) return front_->pixel_sample_share(hit);
        Hit mirrored = hit;
        mirrored.wi = flip_z(hit.wi);
        return back_->pixel_sample_share(mirrored);
    }

    // The side's vertex event (delay, colour transfer: e.g. a two-sided `fluorescent`), with
    // wi mirrored on the back side as for the other calls.
    bool has_vertex_event() const override {
        return front_->has_vertex_event() || back_->has_vertex_event();
    }

    VertexEvent sample_vertex_event(const Hit& hit, float u) const override {
        if (hit.wi.z > 0.f && front_->has_vertex_event())
            return front_->sample_vertex_event(hit, u);
        if (hit.wi.z < 0.f && back_->has_vertex_event()) {
            Hit mirrored = hit;
            mirrored.wi = flip_z(hit.wi);
            return back_->sample_vertex_event(mirrored, u);
        }
        return {};  // this side has no event
    }

private:
    std::shared_ptr<Bsdf> front_, back_;
    uint32_t flags_ = 0;
};

}  // namespace

FEMTO_PLUGIN(TwoSided, femto::PluginKind::Bsdf, "twosided",
             "Two-sided adapter: uses the nested material on both sides of the surface",
             {{"bsdf", "bsdf", "",
               "nested <bsdf> (unnamed children allowed): one for both sides, or two for the "
               "front and back side"}})
