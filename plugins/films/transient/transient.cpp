// Time-resolved film (x-y-t cube): every contribution is reconstructed in space by the
// <rfilter> and in time by the <tfilter> (histogram by default) on a grid of `bins` bins.
// Writes OUTBASE.exr (one EXR part per bin plus a depth part), OUTBASE_steady.exr (the
// time-integrated image), OUTBASE.png (its preview) and, with --npy, OUTBASE.npy.
//
// Memory: the cube (W*H*T*3 floats) is allocated once; per-pixel filter weights and depth
// sums are doubles. Blocks hold one tile (plus the filter border) of the cube each. Sums are
// accumulated per sample, then per pass in a block, then into the cube, so a single small
// contribution is never added directly to a large running total.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>

#include "femto/film.h"
#include "femto/image_io.h"
#include "femto/log.h"
#include "femto/plugin.h"
#include "femto/tfilter.h"
#include "femto/time.h"
#include "femto/viz.h"

namespace {

using namespace femto;

struct PixelWeights {
    double weight = 0;        // sum of filter weights of all samples
    double weight2 = 0;       // sum of their squares (effective sample count, aovs="variance")
    double depth_sum = 0;     // sum of w * sensor distance over samples that hit something
    double depth_weight = 0;  // sum of w over those samples
};

class TransientFilm;

class CubeBlock final : public FilmBlock {
public:
    CubeBlock(const TransientFilm& film, int x0, int y0, int w, int h, int border);
    void put(Vec2 pos, const ContributionList& sample) override;

    const TransientFilm& film_;
    int x0_, y0_, w_, h_, bins_;
    std::vector<float> cube_;   // [h][w][bins][3]
    std::vector<float> count_;  // [h][w][bins] contributions per bin (aovs="count")
    std::vector<float> sq_;     // [h][w][bins][3] sum of w * (per-sample bin value)^2
    std::vector<PixelWeights> weights_;
    std::vector<BinWeight> scratch_;
    std::vector<std::pair<int, Color>> sample_bins_;  // one sample's value per bin
    uint64_t invalid_ = 0;
};

class TransientFilm final : public Film {
public:
    explicit TransientFilm(const Properties& props) : Film(props), grid_(read_time_grid(props)) {
        world_time_ = props.get_bool("world_time", false);
        exposure_ = float(props.get_float("exposure", 0.0));
        const std::string aovs = props.get_string("aovs", "");
        for (size_t pos = 0; pos < aovs.size();) {
            size_t end = aovs.find(',', pos);
            if (end == std::string::npos) end = aovs.size();
            std::string item = aovs.substr(pos, end - pos);
            item.erase(0, item.find_first_not_of(' '));
            item.erase(item.find_last_not_of(' ') + 1);
            if (item == "count")
                count_enabled_ = true;
            else if (item == "variance")
                variance_enabled_ = true;
            else
                props.fail("aovs", fmt::format("unknown AOV \"{}\"; valid: count, variance", item));
            pos = end + 1;
        }
        auto filters = props.objects(PluginKind::TemporalFilter);
        if (filters.size() > 1) props.fail("tfilter", "a film takes at most one <tfilter>");
        tfilter_ = std::static_pointer_cast<TemporalFilter>(
            filters.empty()
                ? create_default_object(PluginKind::TemporalFilter, "histogram", props.location())
                : filters[0]);
        const size_t pixels = size_t(width_) * size_t(height_);
        const double bytes = double(pixels) * grid_.bins * 3 * sizeof(float);
        if (bytes > double(size_t(1) << 36))
            props.fail("bins", fmt::format("the cube would need {:.1f} GiB (limit 64 GiB)",
                                           bytes / double(1 << 30)));
        const double total =
            bytes * (1 + (variance_enabled_ ? 1 : 0) + (count_enabled_ ? 1.0 / 3 : 0));
        const double ram = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
        if (ram > 0 && total > 0.75 * ram)
            props.fail("bins",
                       fmt::format("the cube and its AOVs would need {:.1f} GiB, more than 3/4 of "
                                   "this machine's {:.1f} GiB of memory",
                                   total / double(1 << 30), ram / double(1 << 30)));
        cube_.assign(pixels * size_t(grid_.bins) * 3, 0.f);
        if (count_enabled_) count_.assign(pixels * size_t(grid_.bins), 0.f);
        if (variance_enabled_) sq_.assign(cube_.size(), 0.f);
        weights_.resize(pixels);
    }

    std::unique_ptr<FilmBlock> make_block(int x0, int y0, int w, int h) const override {
        return std::make_unique<CubeBlock>(*this, x0, y0, w, h, filter_border());
    }

    void merge(const FilmBlock& b) override {
        const auto& block = static_cast<const CubeBlock&>(b);
        invalid_ += block.invalid_;
        const size_t T3 = size_t(grid_.bins) * 3;
        for (int by = 0; by < block.h_; ++by) {
            const int y = block.y0_ + by;
            if (y < 0 || y >= height_) continue;
            for (int bx = 0; bx < block.w_; ++bx) {
                const int x = block.x0_ + bx;
                if (x < 0 || x >= width_) continue;
                const size_t src = size_t(by) * size_t(block.w_) + size_t(bx);
                const size_t dst = size_t(y) * size_t(width_) + size_t(x);
                const PixelWeights& s = block.weights_[src];
                if (s.weight == 0) continue;
                PixelWeights& d = weights_[dst];
                d.weight += s.weight;
                d.weight2 += s.weight2;
                d.depth_sum += s.depth_sum;
                d.depth_weight += s.depth_weight;
                const float* in = &block.cube_[src * T3];
                float* out = &cube_[dst * T3];
                for (size_t i = 0; i < T3; ++i) out[i] += in[i];
                if (variance_enabled_) {
                    const float* qin = &block.sq_[src * T3];
                    float* qout = &sq_[dst * T3];
                    for (size_t i = 0; i < T3; ++i) qout[i] += qin[i];
                }
                if (count_enabled_) {
                    const float* cin = &block.count_[src * size_t(grid_.bins)];
                    float* cout = &count_[dst * size_t(grid_.bins)];
                    for (int i = 0; i < grid_.bins; ++i) cout[i] += cin[i];
                }
            }
        }
    }

    void start_pass(uint32_t pass) override { tfilter_->start_pass(pass); }
    double max_path_length() const override {
        // In world time the sensor segment is subtracted later, so paths may run that much
        // longer; the integrator cannot know it in advance, so do not cut them early.
        return world_time_ ? std::numeric_limits<double>::infinity()
                           : grid_.end() + tfilter_->max_radius();
    }

    std::vector<float> steady_image() const override {
        const size_t pixels = size_t(width_) * size_t(height_), T = size_t(grid_.bins);
        std::vector<float> rgb(pixels * 3, 0.f);
        for (size_t p = 0; p < pixels; ++p) {
            if (weights_[p].weight == 0) continue;
            double sum[3] = {0, 0, 0};
            for (size_t t = 0; t < T; ++t)
                for (int c = 0; c < 3; ++c) sum[c] += cube_[(p * T + t) * 3 + c];
            for (int c = 0; c < 3; ++c) rgb[3 * p + c] = float(sum[c] / weights_[p].weight);
        }
        return rgb;
    }

    /// 1 / (sum of filter weights) per pixel: the outputs are the cube times this, applied
    /// while streaming so that writing needs no second copy of the cube.
    std::vector<float> pixel_normalisation() const {
        std::vector<float> scale(weights_.size(), 0.f);
        for (size_t p = 0; p < weights_.size(); ++p)
            if (weights_[p].weight > 0) scale[p] = float(1.0 / weights_[p].weight);
        return scale;
    }

    std::vector<std::string> write(const std::string& out_base,
                                   const RenderInfo& info) const override {
        if (invalid_ > 0)
            log_warning(fmt::format("{} contributions with NaN or infinite radiance were discarded",
                                    invalid_));
        const size_t pixels = size_t(width_) * size_t(height_);
        std::vector<float> depth(pixels, -1.f);
        for (size_t p = 0; p < pixels; ++p)
            if (weights_[p].depth_weight > 0)
                depth[p] = float(weights_[p].depth_sum / weights_[p].depth_weight);
        const io::Attributes attrs =
            io::time_resolved_attributes(grid_, info, world_time_, tfilter_->type_name());
        const std::vector<float> scale = pixel_normalisation();
        std::vector<std::string> files;
        files.push_back(out_base + ".exr");
        io::write_exr_cube(files.back(), width_, height_, grid_.bins, cube_.data(), depth.data(),
                           attrs, scale.data());
        const std::vector<float> steady = steady_image();
        files.push_back(out_base + "_steady.exr");
        io::write_exr_rgb(files.back(), width_, height_, steady.data(), attrs);
        files.push_back(out_base + ".png");
        io::write_png_preview(files.back(), width_, height_, steady.data(), exposure_);
        if (info.write_npy) {
            files.push_back(out_base + ".npy");
            io::write_npy(files.back(), {size_t(height_), size_t(width_), size_t(grid_.bins), 3},
                          cube_.data(), scale.data());
        }
        if (variance_enabled_) {
            // Variance of each pixel-bin estimate (a weighted mean of per-sample values):
            // (E_w[v^2] - E_w[v]^2) / (n_eff - 1), n_eff = (sum w)^2 / sum w^2.
            const size_t T3 = size_t(grid_.bins) * 3;
            std::vector<float> var(cube_.size(), 0.f);
            for (size_t p = 0; p < pixels; ++p) {
                const PixelWeights& pw = weights_[p];
                if (!(pw.weight > 0) || !(pw.weight2 > 0)) continue;
                const double n_eff = pw.weight * pw.weight / pw.weight2;
                if (!(n_eff > 1)) continue;
                for (size_t i = 0; i < T3; ++i) {
                    const double m = cube_[p * T3 + i] / pw.weight,
                                 m2 = sq_[p * T3 + i] / pw.weight;
                    var[p * T3 + i] = float(std::max(0.0, m2 - m * m) / (n_eff - 1));
                }
            }
            files.push_back(out_base + "_variance.npy");
            io::write_npy(files.back(), {size_t(height_), size_t(width_), size_t(grid_.bins), 3},
                          var.data());
        }
        if (count_enabled_) {
            files.push_back(out_base + "_count.npy");
            io::write_npy(files.back(), {size_t(height_), size_t(width_), size_t(grid_.bins)},
                          count_.data());
        }
        return files;
    }

    TimeGrid grid_;
    bool world_time_ = false, count_enabled_ = false, variance_enabled_ = false;
    float exposure_ = 0;
    std::shared_ptr<TemporalFilter> tfilter_;
    std::vector<float> cube_, count_, sq_;
    std::vector<PixelWeights> weights_;
    uint64_t invalid_ = 0;
};

CubeBlock::CubeBlock(const TransientFilm& film, int x0, int y0, int w, int h, int border)
    : film_(film),
      x0_(x0 - border),
      y0_(y0 - border),
      w_(w + 2 * border),
      h_(h + 2 * border),
      bins_(film.grid_.bins),
      cube_(size_t(w_) * size_t(h_) * size_t(bins_) * 3, 0.f),
      count_(film.count_enabled_ ? size_t(w_) * size_t(h_) * size_t(bins_) : 0, 0.f),
      sq_(film.variance_enabled_ ? cube_.size() : 0, 0.f),
      weights_(size_t(w_) * size_t(h_)) {}

void CubeBlock::put(Vec2 pos, const ContributionList& sample) {
    const double sensor = sample.sensor_distance();
    for (const auto& c : sample.items())
        if (!c.radiance.is_finite()) {
            ++invalid_;
            return;
        }
    for_each_filter_pixel(
        film_.rfilter(), pos, x0_, y0_, x0_ + w_, y0_ + h_, [&](int x, int y, float w) {
            const size_t local = size_t(y - y0_) * size_t(w_) + size_t(x - x0_);
            PixelWeights& pw = weights_[local];
            pw.weight += w;
            pw.weight2 += double(w) * w;
            if (sensor >= 0) {
                pw.depth_sum += w * sensor;
                pw.depth_weight += w;
            }
            const uint64_t pixel = uint64_t(y) * uint64_t(film_.width()) + uint64_t(x);
            float* px = &cube_[local * size_t(bins_) * 3];
            if (!sq_.empty()) {
                // Variance needs this sample's value per bin (several contributions may share
                // a bin), then w * v into the cube and w * v^2 into the second moment.
                sample_bins_.clear();
                for (const auto& c : sample.items()) {
                    const double t =
                        film_.world_time_ ? c.path_length - std::max(0.0, sensor) : c.path_length;
                    scratch_.clear();
                    film_.tfilter_->splat(film_.grid_, pixel, t, scratch_);
                    for (const BinWeight& bw : scratch_)
                        sample_bins_.push_back({bw.bin, c.radiance * bw.weight});
                }
                std::sort(sample_bins_.begin(), sample_bins_.end(),
                          [](const auto& a, const auto& b) { return a.first < b.first; });
                float* q = &sq_[local * size_t(bins_) * 3];
                for (size_t i = 0; i < sample_bins_.size();) {
                    const int bin = sample_bins_[i].first;
                    Color v;
                    int n = 0;
                    for (; i < sample_bins_.size() && sample_bins_[i].first == bin; ++i, ++n)
                        v += sample_bins_[i].second;
                    for (int ch = 0; ch < 3; ++ch) {
                        px[size_t(bin) * 3 + ch] += w * v[ch];
                        q[size_t(bin) * 3 + ch] += w * v[ch] * v[ch];
                    }
                    if (!count_.empty()) count_[local * size_t(bins_) + size_t(bin)] += float(n);
                }
                return;
            }
            for (const auto& c : sample.items()) {
                const double t =
                    film_.world_time_ ? c.path_length - std::max(0.0, sensor) : c.path_length;
                scratch_.clear();
                film_.tfilter_->splat(film_.grid_, pixel, t, scratch_);
                for (const BinWeight& bw : scratch_) {
                    const float s = w * bw.weight;
                    float* v = px + size_t(bw.bin) * 3;
                    v[0] += s * c.radiance.r;
                    v[1] += s * c.radiance.g;
                    v[2] += s * c.radiance.b;
                    if (!count_.empty()) count_[local * size_t(bins_) + size_t(bw.bin)] += 1.f;
                }
            }
        });
}

}  // namespace

FEMTO_PLUGIN(
    TransientFilm, femto::PluginKind::Film, "transient",
    "Time-resolved film: an x-y-t cube of radiance, one EXR part per time bin",
    {{"width", "integer", "768", "image width in pixels"},
     {"height", "integer", "576", "image height in pixels"},
     FEMTO_TIME_GRID_PARAMS,
     {"world_time", "boolean", "false",
      "bin by world time (the sensor segment removed, eq. 4.1) instead of camera time"},
     {"aovs", "string", "",
      "comma-separated: \"count\" writes OUTBASE_count.npy (contributions per pixel and bin), "
      "\"variance\" OUTBASE_variance.npy (variance of each pixel-bin estimate)"},
     {"exposure", "float", "0", "exposure of the PNG preview, in stops"},
     {"rfilter", "rfilter", "gaussian", "spatial reconstruction filter (nested)"},
     {"tfilter", "tfilter", "histogram", "temporal reconstruction (nested)"}})
