// Steady-state RGB film: filtered, weighted accumulation in double precision, written as an
// OpenEXR file plus a tone-mapped PNG preview. An integrator's AOV channels
// (Integrator::aov_names()) are accumulated with the same filter weights and written as extra
// named channels of the EXR.
#include <fmt/format.h>

#include <atomic>
#include <cmath>

#include "femto/film.h"
#include "femto/image_io.h"
#include "femto/log.h"
#include "femto/plugin.h"
#include "femto/properties.h"
#include "femto/viz.h"

namespace {

using namespace femto;

// Weighted sums of one pixel: sum(w * L) per channel and sum(w).
struct PixelSum {
    double rgb[3] = {0, 0, 0};
    double weight = 0;
};

class HdrBlock final : public FilmBlock {
public:
    HdrBlock(const ReconstructionFilter& filter, int x0, int y0, int w, int h, int border,
             size_t aovs)
        : filter_(filter),
          x0_(x0 - border),
          y0_(y0 - border),
          w_(w + 2 * border),
          h_(h + 2 * border),
          aov_count_(aovs),
          pixels_(size_t(w_) * size_t(h_)),
          aov_sums_(pixels_.size() * aovs) {}

    void put(Vec2 pos, const ContributionList& sample) override {
        if (!accept_sample(sample, rejected_)) return;
        Color L;
        for (const auto& c : sample.items()) L += c.radiance;
        for_each_filter_pixel(
            filter_, pos, x0_, y0_, x0_ + w_, y0_ + h_, [&](int x, int y, float w) {
                const size_t i = size_t(y - y0_) * size_t(w_) + size_t(x - x0_);
                PixelSum& p = pixels_[i];
                for (int c = 0; c < 3; ++c) p.rgb[c] += double(w) * double(L[c]);
                if (!sample.is_splat()) p.weight += w;  // else add_splat_weight()
                if (aov_count_ > 0 && sample.aovs().size() == aov_count_)
                    for (size_t k = 0; k < aov_count_; ++k)
                        aov_sums_[i * aov_count_ + k] += double(w) * double(sample.aovs()[k]);
            });
    }

    const ReconstructionFilter& filter_;
    int x0_, y0_, w_, h_;
    size_t aov_count_;
    std::vector<PixelSum> pixels_;
    std::vector<double> aov_sums_;  // [pixel][aov]: sum(w * value)
    RejectedContributions rejected_;
};

class HdrFilm final : public Film {
public:
    explicit HdrFilm(const Properties& props) : Film(props) {
        const std::string pf = props.get_string("pixel_format", "rgb");
        if (pf != "rgb")
            props.fail("pixel_format", "hdrfilm writes RGB; pixel_format must be \"rgb\"");
        const std::string ff = props.get_string("file_format", "openexr");
        if (ff != "openexr" && ff != "exr" && ff != "png")
            props.fail("file_format",
                       "file_format must be openexr or png (femto always writes both "
                       "name.exr and a name.png preview)");
        // Mitsuba 0.6 parameters that change nothing femto writes: accepted with a note.
        if (props.get_bool("banner", false))
            log_note(props.location_of("banner"), "femto ignores banner=true (it draws no banner)");
        if (props.get_bool("high_quality_edges", false))
            log_note(props.location_of("high_quality_edges"),
                     "femto ignores high_quality_edges=true (camera samples stay inside the film)");
        const std::string cf = props.get_string("component_format", "float32");
        if (cf != "float32" && cf != "float16" && cf != "uint32")
            props.fail("component_format",
                       "component_format must be float16, float32 or uint32, not \"" + cf + "\"");
        if (cf != "float32")
            log_note(props.location_of("component_format"),
                     "femto ignores component_format=" + cf + " (its EXR is always float32)");
        exposure_ = float(props.get_float("exposure", 0.0));
        border_ = std::max(0, int(std::ceil(rfilter_->radius() - 0.5f)));
        pixels_.resize(size_t(width_) * size_t(height_));
    }

    std::unique_ptr<FilmBlock> make_block(int x0, int y0, int w, int h) const override {
        return std::make_unique<HdrBlock>(*rfilter_, x0, y0, w, h, border_, aov_names_.size());
    }

    // The renderer never merges overlapping blocks concurrently, so the pixels need no lock
    // (the rejected counts are atomics).
    void merge(const FilmBlock& block_in) override {
        const auto& block = static_cast<const HdrBlock&>(block_in);
        add_rejected(block.rejected_);
        for (int by = 0; by < block.h_; ++by) {
            const int y = block.y0_ + by;
            if (y < 0 || y >= height_) continue;
            for (int bx = 0; bx < block.w_; ++bx) {
                const int x = block.x0_ + bx;
                if (x < 0 || x >= width_) continue;
                const PixelSum& src = block.pixels_[size_t(by) * size_t(block.w_) + size_t(bx)];
                PixelSum& dst = pixels_[size_t(y) * size_t(width_) + size_t(x)];
                for (int c = 0; c < 3; ++c) dst.rgb[c] += src.rgb[c];
                dst.weight += src.weight;
                const size_t n = aov_names_.size(), si = size_t(by) * size_t(block.w_) + size_t(bx),
                             di = size_t(y) * size_t(width_) + size_t(x);
                for (size_t k = 0; k < n; ++k) aov_sums_[di * n + k] += block.aov_sums_[si * n + k];
            }
        }
    }

    void add_splat_weight(double samples_per_pixel) override {
        const std::vector<double> wx = filter_weight_integrals(true),
                                  wy = filter_weight_integrals(false);
        for (int y = 0; y < height_; ++y)
            for (int x = 0; x < width_; ++x)
                pixels_[size_t(y) * size_t(width_) + size_t(x)].weight +=
                    samples_per_pixel * wy[size_t(y)] * wx[size_t(x)];
    }

    void prepare_aovs(const std::vector<std::string>& names, const Object&) override {
        if (names == aov_names_) return;
        aov_names_ = names;
        aov_sums_.assign(pixels_.size() * names.size(), 0.0);
    }

    // The AOV channels' per-pixel averages, [pixel][aov].
    std::vector<float> aov_image() const {
        const size_t n = aov_names_.size();
        std::vector<float> out(pixels_.size() * n, 0.f);
        for (size_t i = 0; i < pixels_.size(); ++i)
            if (pixels_[i].weight > 0)
                for (size_t k = 0; k < n; ++k)
                    out[i * n + k] = float(aov_sums_[i * n + k] / pixels_[i].weight);
        return out;
    }

    std::vector<Accumulator> accumulators() override {
        static_assert(sizeof(PixelSum) == 4 * sizeof(double));
        return {Accumulator::of_doubles(pixels_), Accumulator::of(aov_sums_)};
    }

    std::vector<float> steady_image() const override {
        std::vector<float> rgb(pixels_.size() * 3);
        for (size_t i = 0; i < pixels_.size(); ++i)
            for (int c = 0; c < 3; ++c)
                rgb[3 * i + c] =
                    pixels_[i].weight > 0 ? float(pixels_[i].rgb[c] / pixels_[i].weight) : 0.f;
        return rgb;
    }

    std::vector<std::string> write(const std::string& out_base,
                                   const RenderInfo& info) const override {
        const std::vector<float> rgb = steady_image();
        const io::Attributes attrs = io::render_attributes(info);
        io::OutputSet files;
        const std::vector<float> aovs = aov_image();
        io::write_exr_rgb(files.add(out_base + ".exr"), width_, height_, rgb.data(), attrs, nullptr,
                          {aov_names_, aovs.data()});
        io::write_png_preview(files.add(out_base + ".png"), width_, height_, rgb.data(), exposure_);
        return files.commit();
    }

private:
    float exposure_ = 0;
    int border_ = 0;
    std::vector<PixelSum> pixels_;
    std::vector<std::string> aov_names_;
    std::vector<double> aov_sums_;  // [pixel][aov]: sum(w * value)
};

}  // namespace

FEMTO_PLUGIN(HdrFilm, femto::PluginKind::Film, "hdrfilm",
             "Steady-state RGB film: name.exr (float, with the integrator's AOV channels) plus a "
             "name.png preview",
             {{"exposure", "float", "0", "exposure of the PNG preview, in stops"},
              {"pixel_format", "string", "rgb", "accepted for Mitsuba compatibility; only rgb"},
              {"file_format", "string", "openexr",
               "accepted for Mitsuba compatibility; EXR and PNG are always written"},
              {"banner", "boolean", "false",
               "accepted for Mitsuba compatibility; femto draws no banner"},
              {"high_quality_edges", "boolean", "false",
               "accepted for Mitsuba 0.6 compatibility; samples stay inside the film"},
              {"component_format", "string", "float32",
               "float16, float32 or uint32, accepted for Mitsuba compatibility; the EXR is "
               "always float32"}})
