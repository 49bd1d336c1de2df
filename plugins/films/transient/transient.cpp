// Time-resolved film (x-y-t cube): every contribution is reconstructed in space by the
// <rfilter> and in time by the <tfilter> (histogram by default) on a grid of `bins` bins.
// Writes OUTBASE.exr (the frames stacked top to bottom, plus a depth part), OUTBASE_steady.exr
// (the time-integrated image), OUTBASE.png (its preview) and, with --npy, OUTBASE.npy, as one
// io::OutputSet: the files replace earlier outputs together or not at all.
//
// Memory: the cube (W*H*T*3 floats) is allocated once; per-pixel filter weights and depth
// sums are doubles. Blocks hold one tile (plus the filter border) of the cube each, in double.
// Sums are accumulated per sample, then per pass in a block, then into the cube, so a single
// small contribution is never added directly to a large running total.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "femto/film.h"
#include "femto/image_io.h"
#include "femto/plugin.h"
#include "femto/tfilter.h"
#include "femto/time.h"
#include "femto/viz.h"

namespace {

using namespace femto;

class TransientFilm;

// A block's sums. Kept all-zero between uses and recycled through the film's pool: a pass
// touches few of a pixel's bins, so clearing and merging only the touched (pixel, bin)
// entries, instead of whole tiles of the cube, is what keeps a cube film fast.
struct BlockStorage {
    // Time-major ([bins][h][w]): a contribution splatted over the filter footprint touches a
    // few neighbouring cache lines of one bin rather than one line per pixel.
    // Double: a pass may add many contributions to one entry (a light tracer's splats onto a
    // one-pixel meter: every light path of the pass), and float sums of that many lose digits.
    std::vector<double> cube;  // [bins][h][w][3]
    std::vector<float> count;  // [bins][h][w] contributions per bin (aovs="count")
    std::vector<double> sq;    // [bins][h][w][3] sum of w * (per-sample bin value)^2
    std::vector<PixelSums> weights;
    std::vector<uint64_t> touched_bits;  // one bit per (pixel, bin)
    std::vector<uint32_t> touched;       // the (bin * pixels + pixel) entries set, in order
};

// The splat itself is TimeResolvedBlock's; this block is its storage (slot = block pixel).
class CubeBlock final : public TimeResolvedBlock {
public:
    CubeBlock(const TransientFilm& film, int x0, int y0, int w, int h);
    ~CubeBlock() override;
    void put(Vec2 pos, const ContributionList& sample) override {
        clean_ = false;
        splat(pos, sample, *this);
    }

    // Storage of TimeResolvedBlock::splat().
    size_t slot(int x, int y) const { return size_t(y - y0_) * size_t(w_) + size_t(x - x0_); }
    PixelSums& sums(size_t local) { return st_->weights[local]; }
    void add(size_t local, int bin, float w, const Color& v) {
        const size_t flat = touch(local, bin);
        double* dst = &st_->cube[flat * 3];
        dst[0] += w * v.r;
        dst[1] += w * v.g;
        dst[2] += w * v.b;
        if (count_) st_->count[flat] += 1.f;
    }
    // Variance needs this sample's value per bin (several contributions may share a bin): w * v
    // into the cube and w * v^2 into the second moment.
    bool totals() const { return variance_; }
    void add_total(size_t local, int bin, float w, const Color& v, int n) {
        const size_t flat = touch(local, bin);
        for (int ch = 0; ch < 3; ++ch) {
            st_->cube[flat * 3 + size_t(ch)] += w * v[ch];
            st_->sq[flat * 3 + size_t(ch)] += w * v[ch] * v[ch];
        }
        if (count_) st_->count[flat] += float(n);
    }

    /// Index of (local pixel, bin) in the storage; marks it as holding data.
    size_t touch(size_t local, int bin) {
        const size_t flat = size_t(bin) * pixels_ + local;
        uint64_t& word = st_->touched_bits[flat >> 6];
        const uint64_t bit = uint64_t(1) << (flat & 63);
        if (!(word & bit)) {
            word |= bit;
            st_->touched.push_back(uint32_t(flat));
        }
        return flat;
    }

    size_t pixels_;
    std::unique_ptr<BlockStorage> st_;
    bool variance_, count_;      // the storage has the second moment / the counts
    mutable bool clean_ = true;  // all sums merged (and zeroed) since the last put
    // Film pixel of each block pixel, or SIZE_MAX outside the film: merge looks it up instead
    // of dividing twice per touched entry (merge is a hot loop of cube films).
    std::vector<size_t> dst_of_local_;
};

class TransientFilm final : public TimeResolvedFilm {
public:
    explicit TransientFilm(const Properties& props) : TimeResolvedFilm(props) {
        const std::string aovs = props.get_string("aovs", "");
        aovs_location_ = props.location_of("aovs");
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
        const size_t pixels = size_t(width_) * size_t(height_);
        const double bytes = double(pixels) * grid_.bins * 3 * sizeof(float);
        if (bytes > double(size_t(1) << 36))
            props.fail("bins", fmt::format("the cube would need {:.1f} GiB (limit 64 GiB)",
                                           bytes / double(1 << 30)));
        const std::string compression = props.get_string("compression", "rle");
        if (!io::parse_exr_compression(compression, exr_.compression))
            props.fail("compression", fmt::format("unknown compression \"{}\"; valid: none, rle, "
                                                  "zips, zip, piz",
                                                  compression));
        if (int64_t(height_) * grid_.bins > std::numeric_limits<int>::max())
            props.fail("bins",
                       fmt::format("height x bins = {} exceeds the {} rows an EXR image "
                                   "can hold",
                                   int64_t(height_) * grid_.bins, std::numeric_limits<int>::max()));
        // Writing adds at most ~1/16 of the cube (write_exr_cube's frame batches; the .npy
        // files stream a pixel at a time): 1/8 keeps a margin for OpenEXR's line buffers.
        const double total =
            bytes * (1 + (variance_enabled_ ? 1 : 0) + (count_enabled_ ? 1.0 / 3 : 0) + 1.0 / 8);
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
        if (auto pilot = make_pilot_block(x0, y0, w, h)) return pilot;
        return std::make_unique<CubeBlock>(*this, x0, y0, w, h);
    }

    // The variance AOV's formula is that of a weighted mean of camera samples; splats carry
    // no per-sample weight.
    void prepare_splats(bool) override {
        if (variance_enabled_)
            throw SceneError(aovs_location_,
                             "aovs=\"variance\" needs an integrator whose "
                             "samples are camera samples; this one splats "
                             "light paths onto the film");
    }
    void add_splat_weight(double samples_per_pixel) override {
        add_expected_weight(samples_per_pixel, weights_);
    }

    // A block stores every bin of its pixels (cube, second moment, counts, touched bits).
    size_t block_bytes_per_pixel() const override {
        const size_t per_bin =
            3 * sizeof(double) * (variance_enabled_ ? 2 : 1) + (count_enabled_ ? sizeof(float) : 0);
        return size_t(grid_.bins) * per_bin + size_t(grid_.bins + 7) / 8;
    }

    /// A zeroed storage for a block of `pixels` pixels, recycled when possible.
    std::unique_ptr<BlockStorage> acquire_storage(size_t pixels) const {
        std::unique_ptr<BlockStorage> st;
        {
            std::lock_guard<std::mutex> lock(pool_mutex_);
            if (!pool_.empty()) {
                st = std::move(pool_.back());
                pool_.pop_back();
            }
        }
        if (!st) st = std::make_unique<BlockStorage>();
        const size_t entries = pixels * size_t(grid_.bins);
        if (st->weights.size() < pixels) {  // growing keeps the all-zero invariant
            st->weights.resize(pixels);
            st->cube.resize(entries * 3, 0.0);
            if (variance_enabled_) st->sq.resize(entries * 3, 0.0);
            if (count_enabled_) st->count.resize(entries, 0.f);
            st->touched_bits.resize((entries + 63) / 64, 0);
        }
        return st;
    }
    void release_storage(std::unique_ptr<BlockStorage> st) const {
        std::lock_guard<std::mutex> lock(pool_mutex_);
        pool_.push_back(std::move(st));
    }

    void merge(const FilmBlock& b) override {
        if (merge_pilot(b)) return;
        const auto& block = static_cast<const CubeBlock&>(b);
        BlockStorage& st = *block.st_;
        merge_rejected(block);
        const size_t bins = size_t(grid_.bins);
        const size_t block_pixels = block.pixels_;
        const std::vector<size_t>& dst_of = block.dst_of_local_;
        for (const uint32_t flat : st.touched) {
            const size_t bin = flat / block_pixels, local = flat - bin * block_pixels;
            const size_t dst = dst_of[local];
            if (dst != SIZE_MAX) {
                for (int c = 0; c < 3; ++c)
                    cube_[(dst * bins + bin) * 3 + c] += float(st.cube[size_t(flat) * 3 + c]);
                if (variance_enabled_)
                    for (int c = 0; c < 3; ++c)
                        sq_[(dst * bins + bin) * 3 + c] += float(st.sq[size_t(flat) * 3 + c]);
                if (count_enabled_) count_[dst * bins + bin] += st.count[flat];
            }
            for (int c = 0; c < 3; ++c) st.cube[size_t(flat) * 3 + c] = 0.0;
            if (variance_enabled_)
                for (int c = 0; c < 3; ++c) st.sq[size_t(flat) * 3 + c] = 0.0;
            if (count_enabled_) st.count[flat] = 0.f;
            st.touched_bits[flat >> 6] = 0;  // whole words: every bit in them is in `touched`
        }
        st.touched.clear();
        for (size_t local = 0; local < block_pixels; ++local) {
            PixelSums& s = st.weights[local];
            if (s.empty()) continue;
            const size_t dst = dst_of[local];
            if (dst != SIZE_MAX) weights_[dst] += s;
            s = PixelSums();
        }
        block.clean_ = true;
    }

    std::vector<Accumulator> accumulators() override {
        // count_ and sq_ are empty unless their AOVs are on.
        return with_window_accumulators({Accumulator::of(cube_), Accumulator::of(count_),
                                         Accumulator::of(sq_), Accumulator::of_doubles(weights_)});
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

    /// Image mean of the energy the temporal kernel moved out of the window (per pixel,
    /// normalised like the image): adding it to the steady image's mean gives what a
    /// histogram would sum to over the window.
    std::pair<std::string, std::string> window_spill_attribute() const {
        double mean[3] = {0, 0, 0};
        for (const PixelSums& pw : weights_)
            if (pw.weight > 0)
                for (int c = 0; c < 3; ++c) mean[c] += pw.spill[c] / pw.weight;
        const double n = double(weights_.size());
        return {"femto:window_spill",
                fmt::format("{:.9g} {:.9g} {:.9g}", mean[0] / n, mean[1] / n, mean[2] / n)};
    }

    std::vector<std::string> write(const std::string& out_base,
                                   const RenderInfo& info) const override {
        warn_empty_window();
        const size_t pixels = size_t(width_) * size_t(height_);
        std::vector<float> depth(pixels);
        for (size_t p = 0; p < pixels; ++p) depth[p] = weights_[p].depth();
        io::Attributes attrs = io::time_resolved_attributes(grid_, info, tfilter_->type_name());
        // A spreading filter, or an integrator's own time kernel (photon mapping), spills.
        const bool spilled = std::any_of(weights_.begin(), weights_.end(), [](const PixelSums& s) {
            return s.spill[0] != 0 || s.spill[1] != 0 || s.spill[2] != 0;
        });
        if (tfilter_->max_radius() > 0 || spilled) attrs.push_back(window_spill_attribute());
        const std::vector<float> scale = pixel_normalisation();
        const std::vector<size_t> shape = {size_t(height_), size_t(width_), size_t(grid_.bins), 3};
        io::OutputSet files;  // all appear together, or none
        io::write_exr_cube(files.add(out_base + ".exr"), width_, height_, grid_.bins, cube_.data(),
                           depth.data(), attrs, scale.data(), exr_);
        const std::vector<float> steady = steady_image();
        io::write_exr_rgb(files.add(out_base + "_steady.exr"), width_, height_, steady.data(),
                          attrs);
        io::write_png_preview(files.add(out_base + ".png"), width_, height_, steady.data(),
                              exposure_);
        if (info.write_npy)
            io::write_npy(files.add(out_base + ".npy"), shape, cube_.data(), scale.data());
        if (variance_enabled_)
            io::write_npy_pixels(files.add(out_base + "_variance.npy"), shape,
                                 [&](size_t p, float* out) { pixel_variance(p, out); });
        if (count_enabled_)
            io::write_npy(files.add(out_base + "_count.npy"),
                          {size_t(height_), size_t(width_), size_t(grid_.bins)}, count_.data());
        return files.commit();
    }

    /// Variance of each of pixel p's bin estimates (a weighted mean of per-sample values):
    /// (E_w[v^2] - E_w[v]^2) / (n_eff - 1), n_eff = (sum w)^2 / sum w^2; 0 where undefined.
    void pixel_variance(size_t p, float* out) const {
        const size_t T3 = size_t(grid_.bins) * 3;
        std::fill(out, out + T3, 0.f);
        const PixelSums& pw = weights_[p];
        if (!(pw.weight > 0) || !(pw.weight2 > 0)) return;
        const double n_eff = pw.weight * pw.weight / pw.weight2;
        if (!(n_eff > 1)) return;
        for (size_t i = 0; i < T3; ++i) {
            const double m = cube_[p * T3 + i] / pw.weight, m2 = sq_[p * T3 + i] / pw.weight;
            out[i] = float(std::max(0.0, m2 - m * m) / (n_eff - 1));
        }
    }

    io::ExrCubeOptions exr_;
    SourceLocation aovs_location_;
    bool count_enabled_ = false, variance_enabled_ = false;
    std::vector<float> cube_, count_, sq_;
    mutable std::mutex pool_mutex_;
    mutable std::vector<std::unique_ptr<BlockStorage>> pool_;
    std::vector<PixelSums> weights_;
};

CubeBlock::CubeBlock(const TransientFilm& film, int x0, int y0, int w, int h)
    : TimeResolvedBlock(film, x0, y0, w, h),
      pixels_(size_t(w_) * size_t(h_)),
      st_(film.acquire_storage(pixels_)),
      variance_(!st_->sq.empty()),
      count_(!st_->count.empty()),
      dst_of_local_(pixels_) {
    for (int by = 0; by < h_; ++by)
        for (int bx = 0; bx < w_; ++bx) {
            const int x = x0_ + bx, y = y0_ + by;
            dst_of_local_[size_t(by) * size_t(w_) + size_t(bx)] =
                x < 0 || x >= film.width() || y < 0 || y >= film.height()
                    ? SIZE_MAX
                    : size_t(y) * size_t(film.width()) + size_t(x);
        }
}

CubeBlock::~CubeBlock() {
    if (!clean_) {  // never merged (an exception): restore the all-zero invariant
        std::fill(st_->cube.begin(), st_->cube.end(), 0.0);
        std::fill(st_->sq.begin(), st_->sq.end(), 0.0);
        std::fill(st_->count.begin(), st_->count.end(), 0.f);
        std::fill(st_->touched_bits.begin(), st_->touched_bits.end(), 0);
        std::fill(st_->weights.begin(), st_->weights.end(), PixelSums());
        st_->touched.clear();
    }
    static_cast<const TransientFilm&>(film_).release_storage(std::move(st_));
}

}  // namespace

FEMTO_PLUGIN(
    TransientFilm, femto::PluginKind::Film, "transient",
    "Time-resolved film: an x-y-t cube of radiance (EXR frames stacked top to bottom)",
    {{"compression", "string", "rle",
      "OpenEXR compression of OUTBASE.exr: none, rle, zips, zip or piz (docs/outputs.md "
      "compares them)"},
     {"aovs", "string", "",
      "comma-separated: \"count\" writes OUTBASE_count.npy (contributions per pixel and bin), "
      "\"variance\" OUTBASE_variance.npy (variance of each pixel-bin estimate, by the "
      "formula for independent samples: it overstates the error of ldsampler renders)"}})
