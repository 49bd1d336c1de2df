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
// shape to importance-sample.
//
// With `prefilter`, the material looks the BTF up in its prefiltered hierarchy (thesis ch. 3,
// femto/btf_prefilter.h) at the level and cones a camera ray's pixel footprint selects
// (Hit::footprint): the texel-to-pixel ratio r = the longer of the pixel's two steps in texels,
// times scale_spatial; the light cone = half the pixel's change of the normal (the light's
// direction relative to the surface turns with it) plus the cone of light directions the light
// sample stands for (PixelFootprint::light_cone: the emitter's extent and its direction's turn
// across the pixel, set by the toolkit's light sampling), times scale_light; the view cone = half
// the pixel's change of the view direction relative to the surface (ray direction plus normal),
// times scale_view. The texture is looked up at the pixel's centre (the area a box-filtered
// pixel averages), not at the jittered sample (PixelFootprint::to_pixel_centre); with
// spatial_lookup="footprint", as the exact box mean over the pixel's footprint instead of the
// mip-map's level (docs/btf.md). Rays without a footprint (after the first bounce) see the
// finest level, unfiltered. With `adaptive_spp` (thesis Fig. 3.15), a pixel whose centre ray
// meets the material first takes share(r) of the render's samples per pixel (femto/bsdf.h,
// pixel_sample_share()). A BTF is not reciprocal: paths from the lights evaluate it through
// eval_adjoint(), with the camera's side as the view.
#include "femto/btf.h"

#include <cmath>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "femto/bsdf.h"
#include "femto/btf_prefilter.h"
#include "femto/direction_mesh.h"
#include "femto/log.h"
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
          scale_(non_negative(props, "scale")),
          scale_spatial_(positive(props, "scale_spatial")),
          scale_light_(positive(props, "scale_light")),
          scale_view_(positive(props, "scale_view")) {
        // Read every prefilter setting, used or not, so that each is checked (and none is
        // reported unused) whether or not `prefilter` is on.
        const bool prefilter = props.get_bool("prefilter", false);
        const btf::PrefilterSettings settings = prefilter_settings(props);
        const btf::PcaSettings pca = pca_settings(props);
        const bool cache = props.get_bool("cache", true);
        const std::string lookup = props.get_string("spatial_lookup", "mipmap");
        if (lookup != "mipmap" && lookup != "footprint")
            props.fail("spatial_lookup",
                       "spatial_lookup must be mipmap or footprint, not \"" + lookup + "\"");
        box_footprint_ = lookup == "footprint";
        if (prefilter) hierarchy_ = build_hierarchy(props, settings, pca, cache);
        sample_shares_ = sample_shares(props);
    }

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

    bool uses_footprint() const override { return hierarchy_ || !sample_shares_.empty(); }
    bool uses_tangent() const override { return true; }  // the BTF's frame follows dpdu
    bool adapts_sampling() const override { return !sample_shares_.empty(); }
    /// `adaptive_spp`'s share at the pixel's texel-to-pixel ratio: linear in log2 r between
    /// the table's entries, its first and last share beyond them.
    float pixel_sample_share(const Hit& hit) const override {
        if (sample_shares_.empty() || !hit.footprint.valid) return 1.f;
        const double r = texel_ratio(hit.footprint);
        const double x = r > 0 ? std::log2(r) : -1e300;
        if (x <= sample_shares_.front().first) return float(sample_shares_.front().second);
        for (size_t i = 1; i < sample_shares_.size(); ++i) {
            const auto& [x1, s1] = sample_shares_[i];
            const auto& [x0, s0] = sample_shares_[i - 1];
            if (x <= x1) return float(s0 + (s1 - s0) * (x - x0) / (x1 - x0));
        }
        return float(sample_shares_.back().second);
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
    static btf::PrefilterSettings prefilter_settings(const Properties& props) {
        btf::PrefilterSettings settings;
        const std::string filter = props.get_string("filter", "box");
        if (filter == "gaussian")
            settings.kernel = btf::FilterKernel::Gaussian;
        else if (filter == "lanczos")
            settings.kernel = btf::FilterKernel::Lanczos;
        else if (filter != "box")
            props.fail("filter", "filter must be box, gaussian or lanczos, not \"" + filter + "\"");
        settings.cone_angles_deg = cone_angles(props);
        return settings;
    }
    static btf::PcaSettings pca_settings(const Properties& props) {
        btf::PcaSettings pca;
        const int64_t components = props.get_int("components", 16);
        if (components < 1 || components > btf::Hierarchy::kMaxComponents)
            props.fail("components",
                       "components must be 1 to " + std::to_string(btf::Hierarchy::kMaxComponents));
        pca.components = uint32_t(components);
        return pca;
    }
    std::shared_ptr<const btf::Hierarchy> build_hierarchy(const Properties& props,
                                                          const btf::PrefilterSettings& settings,
                                                          const btf::PcaSettings& pca,
                                                          bool cache) const {
        btf::PrefilterReport report;
        auto h =
            btf::prefiltered(props.get_string("filename"), *data_, settings, pca, cache, report);
        if (!report.cache_problem.empty())
            log_warning(props.location_of("filename"),
                        "the prefiltered BTF is not cached: " + report.cache_problem);
        return h;
    }
    /// `adaptive_spp`: "r:s, r:s, ..." pairs of a texel-to-pixel ratio (increasing, > 0) and
    /// the share of the base sample count a pixel at that ratio takes (0 < s <= 1); stored as
    /// (log2 r, s). Empty: no adaptive sampling.
    static std::vector<std::pair<double, double>> sample_shares(const Properties& props) {
        std::vector<std::pair<double, double>> table;
        std::istringstream in(props.get_string("adaptive_spp", ""));
        const char* form =
            "adaptive_spp must be \"ratio:share\" pairs separated by commas, "
            "ratios increasing from above 0 and shares in (0, 1], e.g. \"1:1, "
            "16:0.25\"";
        for (std::string item; std::getline(in, item, ',');) {
            if (item.find_first_not_of(" \t") == std::string::npos && table.empty() && in.eof())
                break;  // the empty default
            char* end = nullptr;
            const double r = std::strtod(item.c_str(), &end);
            if (end == item.c_str() || *end != ':') props.fail("adaptive_spp", form);
            const char* rest = end + 1;
            const double share = std::strtod(rest, &end);
            if (end == rest || std::string(end).find_first_not_of(" \t") != std::string::npos)
                props.fail("adaptive_spp", form);
            if (!(r > 0) || !std::isfinite(r) || !(share > 0 && share <= 1) ||
                (!table.empty() && !(std::log2(r) > table.back().first)))
                props.fail("adaptive_spp", form);
            table.emplace_back(std::log2(r), share);
        }
        return table;
    }
    static std::vector<double> cone_angles(const Properties& props) {
        std::vector<double> angles;
        std::istringstream in(props.get_string("cone_angles", "0, 15, 30, 45"));
        for (std::string item; std::getline(in, item, ',');) {
            char* end = nullptr;
            const double a = std::strtod(item.c_str(), &end);
            if (end == item.c_str() || !std::isfinite(a))
                props.fail("cone_angles", "cone_angles must be numbers separated by commas");
            angles.push_back(a);
        }
        bool increasing = !angles.empty() && angles[0] == 0 && angles.back() <= 90;
        for (size_t i = 1; i < angles.size(); ++i)
            increasing = increasing && angles[i] > angles[i - 1];
        if (!increasing)
            props.fail("cone_angles", "cone_angles must increase from 0 to at most 90 (degrees)");
        return angles;
    }
    static float positive(const Properties& props, const char* name) {
        const double v = props.get_float(name, 1.0);
        if (!(v > 0) || !std::isfinite(v))
            props.fail(name, std::string(name) + " must be a finite number > 0");
        return float(v);
    }
    static float non_negative(const Properties& props, const char* name) {
        const double v = props.get_float(name, 1.0);
        if (!(v >= 0) || !std::isfinite(v))
            props.fail(name, std::string(name) + " must be a finite number >= 0");
        return float(v);
    }

    /// scale * B for the shading-frame directions wi (view) and wo (light).
    Color reflectance(const Hit& hit, const Vec3& wi, const Vec3& wo) const {
        const Vec2 tangent = tangent_direction(hit);
        const Vec3 light = to_btf_frame(wo, tangent), view = to_btf_frame(wi, tangent);
        if (!hierarchy_) return lookup(hit.uv, light, view) * scale_;
        const DirectionMesh::Weights wl = lights_.interpolate(light);
        const DirectionMesh::Weights wv = views_.interpolate(view);
        double ratio = 0, light_cone = 0, view_cone = 0;
        Vec2 uv = hit.uv;
        Color b;
        if (hit.footprint.valid) {
            const PixelFootprint& f = hit.footprint;
            footprint_query(f, ratio, light_cone, view_cone);
            // Centred on the pixel (the area a box-filtered pixel averages), not on the sample.
            uv = uv + f.duv_dx * f.to_pixel_centre.x + f.duv_dy * f.to_pixel_centre.y;
        }
        if (box_footprint_ && hit.footprint.valid)
            b = hierarchy_->lookup_box(uv * uv_scale_, footprint_extent(hit.footprint), light_cone,
                                       view_cone, wl, wv);
        else
            b = hierarchy_->lookup(uv * uv_scale_, ratio, light_cone, view_cone, wl, wv);
        // A filtered reflectance is >= 0; the angular filter's low-order fit can undershoot
        // at hard shadow edges (BTF B's grooves), and the PCA truncation a little anywhere.
        for (int c = 0; c < 3; ++c) b[c] = std::max(b[c], 0.f);
        return b * scale_;
    }

    /// The texel-to-pixel ratio: the longer of the pixel's two steps, in texels.
    double texel_ratio(const PixelFootprint& f) const {
        const btf::Header& h = data_->header();
        auto texels = [&](Vec2 duv) {
            return uv_scale_ * std::hypot(double(duv.x) * h.width, double(duv.y) * h.height);
        };
        return std::max(texels(f.duv_dx), texels(f.duv_dy));
    }
    /// The rectangle (width along u, height along v, in finest-level texels, times
    /// scale_spatial) with the footprint's second moments along u and along v: the pixel's
    /// square maps to the parallelogram of the steps duv_dx and duv_dy, whose extent along u is
    /// hypot(du_dx, du_dy) in that sense (exact when the steps lie along u and v; the
    /// parallelogram's bounding box would blur a sheared footprint more than the pixel does).
    Vec2 footprint_extent(const PixelFootprint& f) const {
        const btf::Header& h = data_->header();
        const float sx = uv_scale_ * float(h.width), sy = uv_scale_ * float(h.height);
        return Vec2(std::hypot(f.duv_dx.x, f.duv_dy.x) * sx,
                    std::hypot(f.duv_dx.y, f.duv_dy.y) * sy) *
               scale_spatial_;
    }
    /// The level and cones a pixel's footprint selects (see the top of this file).
    void footprint_query(const PixelFootprint& f, double& ratio, double& light_cone,
                         double& view_cone) const {
        ratio = scale_spatial_ * texel_ratio(f);
        const double turn = std::max(length(f.dn_dx), length(f.dn_dy));
        light_cone = scale_light_ * (0.5 * turn + f.light_cone);
        view_cone = scale_view_ * 0.5 *
                    std::max(length(f.dd_dx) + length(f.dn_dx), length(f.dd_dy) + length(f.dn_dy));
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
        const btf::BilinearTexels texels = btf::bilinear_texels(uv * uv_scale_, h.width, h.height);
        Color sum(0.f);
        for (int corner = 0; corner < 4; ++corner) {
            const float w = texels.weight[corner];
            if (w == 0.f) continue;
            const uint32_t x = texels.x[corner & 1], y = texels.y[corner >> 1];
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    const float wij = w * wl.weight[i] * wv.weight[j];
                    if (wij > 0.f) sum += data_->value(x, y, wl.index[i], wv.index[j]) * wij;
                }
        }
        return sum;
    }
    std::shared_ptr<const btf::Data> data_;
    DirectionMesh lights_, views_;
    float uv_scale_, scale_;
    float scale_spatial_, scale_light_, scale_view_;
    std::shared_ptr<const btf::Hierarchy> hierarchy_;       // with `prefilter`
    bool box_footprint_ = false;                            // spatial_lookup="footprint"
    std::vector<std::pair<double, double>> sample_shares_;  // `adaptive_spp`: (log2 r, share)
};

}  // namespace

FEMTO_PLUGIN(Btf, femto::PluginKind::Bsdf, "btf",
             "Bidirectional texture function from a Bonn BTF file (BDI, DFMF, FMF)",
             {{"filename", "filename", "", "the BTF file (BDI, DFMF or FMF; see docs/btf.md)"},
              {"uv_scale", "float", "1", "texture repetitions per unit of uv"},
              {"scale", "float", "1", "factor applied to the reflectance"},
              {"prefilter", "bool", "false",
               "look up the prefiltered hierarchy at the camera ray's pixel footprint"},
              {"filter", "string", "box", "prefilter kernel: box, gaussian or lanczos"},
              {"spatial_lookup", "string", "mipmap",
               "mipmap: the level of the footprint's longer side, trilinear (thesis ch. 3); "
               "footprint: the exact mean over the footprint's rectangle (docs/btf.md)"},
              {"cone_angles", "string", "0, 15, 30, 45",
               "half-angles (degrees) of the light and view cones the hierarchy holds"},
              {"scale_spatial", "float", "1", "s_x: factor on the texel-to-pixel ratio"},
              {"scale_light", "float", "1", "s_l: factor on the light cone"},
              {"scale_view", "float", "1", "s_v: factor on the view cone"},
              {"components", "integer", "16",
               "PCA components for files without linear factors (BDI, log data)"},
              {"cache", "bool", "true", "keep the hierarchy in a file next to the BTF"},
              {"adaptive_spp", "string", "",
               "adaptive sampling: \"ratio:share, ...\" pairs; a pixel whose camera ray meets "
               "the BTF first at texel-to-pixel ratio r takes share(r) x spp samples"}})
