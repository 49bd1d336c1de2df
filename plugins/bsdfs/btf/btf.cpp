// btf: a bidirectional texture function read from the University of Bonn's formats (BDI, DFMF,
// FMF; femto/btf.h), as measured in the UBO2003 and UBO2014 databases or written by
// `femto btf synth`. docs/btf.md explains the conventions.
//
// f(x, wi, wo) = scale * B(x, l = wo, v = wi) / pi on the front side, where B is the file's
// reflectance factor (a white Lambertian reads 1): wi looks toward the camera (the view) and wo
// toward the light. The BTF's frame has x along the surface's u tangent (Hit::dpdu) and z along
// the shading normal. Between the sampled directions, B is barycentric in a triangulation of
// the light directions times one of the view directions (DirectionMesh); between texels it is
// bilinear, wrapping around the texture (uv (0, 0) is the texture's bottom-left corner, as for
// `bitmap`; texel row 0 is its top). Sampling is cosine-weighted: measured data has no lobe
// shape to importance-sample. A BTF is not reciprocal: paths from the lights evaluate it through
// eval_adjoint(), with the camera's side as the view.
#include "femto/btf.h"

#include <cmath>
#include <memory>

#include "femto/bsdf.h"
#include "femto/direction_mesh.h"
#include "femto/plugin.h"
#include "femto/warp.h"

namespace {

using namespace femto;

DirectionMesh triangulate(const Properties& props, const std::vector<Vec3>& dirs,
                          const char* which) {
    try {
        return DirectionMesh(dirs);
    } catch (const std::invalid_argument& e) {
        props.fail("filename", std::string("the BTF's ") + which +
                                   " directions cannot be triangulated: " + e.what());
    }
}

class Btf final : public Bsdf {
public:
    explicit Btf(const Properties& props)
        : data_(read_data(props)),
          lights_(triangulate(props, data_->header().lights, "light")),
          views_(triangulate(props, data_->header().views, "view")),
          uv_scale_(positive(props, "uv_scale")),
          scale_(non_negative(props, "scale")) {}

    uint32_t flags() const override { return kBsdfGlossyReflection; }
    bool reciprocal() const override { return false; }  // light and view are not exchangeable

    BsdfSample sample(const Hit& hit, const Vec3& wi, float /*u_lobe*/, Vec2 u) const override {
        BsdfSample s;
        if (wi.z <= 0.f) return s;
        s.wo = warp::square_to_cosine_hemisphere(u);
        s.pdf = warp::cosine_hemisphere_pdf(s.wo);
        if (!(s.pdf > 0.f) || s.wo.z <= 0.f) return BsdfSample{};
        s.sampled_lobe = kBsdfGlossyReflection;
        s.weight = reflectance(hit, wi, s.wo);  // (B / pi) cos / (cos / pi)
        return s;
    }

    Color eval(const Hit& hit, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return Color(0.f);
        return reflectance(hit, wi, wo) * (wo.z * kInvPi);
    }

    float pdf(const Hit&, const Vec3& wi, const Vec3& wo) const override {
        if (wi.z <= 0.f || wo.z <= 0.f) return 0.f;
        return warp::cosine_hemisphere_pdf(wo);
    }

private:
    static std::shared_ptr<const btf::Data> read_data(const Properties& props) {
        const std::string filename = props.get_string("filename");
        try {
            return btf::read(filename);
        } catch (const SceneError& e) {
            props.fail("filename", e.message());
        }
    }
    static float positive(const Properties& props, const char* name) {
        const double v = props.get_float(name, 1.0);
        if (!(v > 0) || !std::isfinite(v)) props.fail(name, std::string(name) + " must be a finite number > 0");
        return float(v);
    }
    static float non_negative(const Properties& props, const char* name) {
        const double v = props.get_float(name, 1.0);
        if (!(v >= 0) || !std::isfinite(v)) props.fail(name, std::string(name) + " must be a finite number >= 0");
        return float(v);
    }

    /// scale * B for the shading-frame directions wi (view) and wo (light).
    Color reflectance(const Hit& hit, const Vec3& wi, const Vec3& wo) const {
        const Vec2 tangent = tangent_direction(hit);
        return lookup(hit.uv, to_btf_frame(wo, tangent), to_btf_frame(wi, tangent)) * scale_;
    }

    /// The u tangent's direction in the shading frame's xy-plane (the shading frame's own s
    /// when the surface has no usable parameterization here).
    static Vec2 tangent_direction(const Hit& hit) {
        const Vec3 t = hit.sh.to_local(hit.dpdu);
        const float len = std::sqrt(t.x * t.x + t.y * t.y);
        return len > 1e-12f ? Vec2(t.x / len, t.y / len) : Vec2(1.f, 0.f);
    }
    static Vec3 to_btf_frame(const Vec3& w, Vec2 tangent) {
        return {w.x * tangent.x + w.y * tangent.y, -w.x * tangent.y + w.y * tangent.x, w.z};
    }

    Color lookup(Vec2 uv, const Vec3& light, const Vec3& view) const {
        const DirectionMesh::Weights wl = lights_.interpolate(light);
        const DirectionMesh::Weights wv = views_.interpolate(view);
        const btf::Header& h = data_->header();
        const double fx = double(uv.x) * uv_scale_ * h.width - 0.5;
        const double fy = (1.0 - double(uv.y) * uv_scale_) * h.height - 0.5;
        const double x0 = std::floor(fx), y0 = std::floor(fy);
        const float tx = float(fx - x0), ty = float(fy - y0);
        Color sum(0.f);
        for (int corner = 0; corner < 4; ++corner) {
            const int dx = corner & 1, dy = corner >> 1;
            const float w = (dx ? tx : 1.f - tx) * (dy ? ty : 1.f - ty);
            if (w == 0.f) continue;
            const uint32_t x = wrap(x0 + dx, h.width), y = wrap(y0 + dy, h.height);
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    const float wij = w * wl.weight[i] * wv.weight[j];
                    if (wij > 0.f) sum += data_->value(x, y, wl.index[i], wv.index[j]) * wij;
                }
        }
        return sum;
    }
    static uint32_t wrap(double i, uint32_t n) {
        const double m = std::fmod(i, double(n));
        return uint32_t(m < 0 ? m + n : m) % n;
    }

    std::shared_ptr<const btf::Data> data_;
    DirectionMesh lights_, views_;
    float uv_scale_, scale_;
};

}  // namespace

FEMTO_PLUGIN(Btf, femto::PluginKind::Bsdf, "btf",
             "Bidirectional texture function from a Bonn BTF file (BDI, DFMF, FMF)",
             {{"filename", "filename", "", "the BTF file (BDI, DFMF or FMF; see docs/btf.md)"},
              {"uv_scale", "float", "1", "texture repetitions per unit of uv"},
              {"scale", "float", "1", "factor applied to the reflectance"}})
