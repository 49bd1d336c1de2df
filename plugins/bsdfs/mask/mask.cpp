// mask: an opacity mask over a nested material (Mitsuba 0.6's and 3's `mask`).
//
// With probability `opacity` (alpha, 1 = opaque) light meets the nested material; otherwise it
// passes straight through (wo = -wi) as if the surface were not there. The transparent part is
// a null interaction: a delta lobe of weight 1 - alpha that sample() picks with probability
// 1 - alpha (sampled_lobe = kBsdfNull, weight 1, pdf 1 - alpha). eval() and pdf() are the
// nested material's scaled by alpha (a delta lobe has no density), so the nested lobes keep
// their sample weights. As in Mitsuba, the opacity is the luminance of the `opacity` value or
// texture; a texture's value is clamped to [0, 1] (a non-finite one counts as opaque), while a
// constant outside [0, 1] or not a number is a located error.
//
// How integrators see it: a mask is an ordinary surface with a delta lobe (as in Mitsuba 3's
// `path`). Light samples are blocked by it; light through its transparent part is found by
// BSDF sampling, the pass-through counting as a bounce toward max_depth. A light tracer, whose
// only way to the camera is a connection, weighs its connections by null_transmission()
// (1 - opacity) instead. Time: the pass-through adds no optical length and no delay (the
// surface has no thickness), so light seen through a mask arrives when it would without it.
// A nested material with a vertex event (fluorescence) is refused: its delay would also apply
// to the light passing through.
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "femto/bsdf.h"
#include "femto/plugin.h"
#include "femto/texture.h"

namespace {

using namespace femto;

std::shared_ptr<Texture> read_opacity(const Properties& props) {
    if (props.has("opacity") && props.type("opacity") != Properties::Type::Object) {
        const Color c = props.get_color("opacity");
        for (int i = 0; i < 3; ++i)
            if (!(c[i] >= 0.f && c[i] <= 1.f))
                props.fail("opacity",
                           "mask \"opacity\" must lie in [0, 1] (0 = transparent, "
                           "1 = opaque), got " +
                               std::to_string(c[i]));
        return std::make_shared<ConstantTexture>(c);
    }
    return get_texture(props, "opacity", Color(0.5f));
}

class Mask final : public Bsdf {
public:
    explicit Mask(const Properties& props) : opacity_(read_opacity(props)) {
        const std::vector<ObjectPtr> children = props.objects(PluginKind::Bsdf);
        if (children.size() != 1)
            props.fail("bsdf",
                       "mask needs exactly one nested <bsdf> (the material of its opaque "
                       "part), but " +
                           std::to_string(children.size()) + " were given");
        nested_ = std::static_pointer_cast<Bsdf>(children[0]);
        if (nested_->has_vertex_event())
            props.fail("bsdf",
                       "mask cannot hold a material with a vertex event (e.g. "
                       "fluorescent): its delay would also apply to the light passing "
                       "through the mask");
        flags_ = nested_->flags() | kBsdfNull;
    }

    uint32_t flags() const override { return flags_; }

    BsdfSample sample(const Hit& hit, const Vec3& wi, float u_lobe, Vec2 u) const override {
        const float alpha = opacity(hit);
        if (u_lobe < alpha) {  // the nested material, its lobe chosen by the rescaled number
            const float u_nested = std::min(u_lobe / alpha, std::nextafter(1.f, 0.f));
            BsdfSample s = nested_->sample(hit, wi, u_nested, u);
            s.pdf *= alpha;  // eval() and pdf() both scale by alpha: the weight stays
            return s;
        }
        BsdfSample s;  // straight through
        s.wo = -wi;
        s.pdf = 1.f - alpha;
        s.eta = 1.f;
        s.sampled_lobe = kBsdfNull;
        s.weight = Color(1.f);
        return s;
    }

    Color eval(const Hit& hit, const Vec3& wi, const Vec3& wo) const override {
        return nested_->eval(hit, wi, wo) * opacity(hit);
    }

    float pdf(const Hit& hit, const Vec3& wi, const Vec3& wo) const override {
        return nested_->pdf(hit, wi, wo) * opacity(hit);
    }

    // What passes straight: the transparent part, and what the nested material lets through.
    bool reciprocal() const override { return nested_->reciprocal(); }
    bool uses_footprint() const override { return nested_->uses_footprint(); }
    bool uses_tangent() const override { return nested_->uses_tangent(); }
    bool adapts_sampling() const override { return nested_->adapts_sampling(); }
    float pixel_sample_share(const Hit& hit) const override {
        return nested_->pixel_sample_share(hit);
    }

    Color null_transmission(const Hit& hit) const override {
        const float alpha = opacity(hit);
        return Color(1.f - alpha) + nested_->null_transmission(hit) * alpha;
    }

private:
    float opacity(const Hit& hit) const {
        const float a = opacity_->eval(hit).luminance();
        return std::isfinite(a) ? std::clamp(a, 0.f, 1.f) : 1.f;
    }

    std::shared_ptr<Texture> opacity_;
    std::shared_ptr<Bsdf> nested_;
    uint32_t flags_ = 0;
};

}  // namespace

FEMTO_PLUGIN(Mask, femto::PluginKind::Bsdf, "mask",
             "Opacity mask: the nested material with probability `opacity`, else straight "
             "pass-through (no delay)",
             {{"opacity", "color|texture", "0.5",
               "opacity in [0, 1] (1 = opaque; the luminance of a colour or texture is used)"},
              {"bsdf", "bsdf", "",
               "nested <bsdf> (unnamed child allowed): the material of the opaque part"}})
