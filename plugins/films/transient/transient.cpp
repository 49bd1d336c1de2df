// Time-resolved film (x-y-t cube): every contribution is reconstructed in space by the
// <rfilter> and in time by the <tfilter> (histogram by default) on a grid of `bins` bins.
// Writes OUTBASE.exr (the frames stacked top to bottom, plus a depth part), OUTBASE_steady.exr
// (the time-integrated image), OUTBASE.png (its preview) and, with --npy, OUTBASE.npy, as one
// io::OutputSet: the files replace earlier outputs together or not at all.
//
// Memory: the cube (W*H*T*3 floats) is allocated once; per-pixel filter weights and depth
// sums are doubles. A block holds, in double, the (pixel, bin) entries its tile (plus the
// filter border) received in a pass.
// Sums are accumulated per sample, then per pass in a block, then into the cube, so a single
// small contribution is never added directly to a large running total; passes beyond the
// 64th add into it by stochastic rounding (PassTotals), which does not drift.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "block_storage.h"
#include "femto/accumulator.h"
#include "femto/film.h"
#include "femto/image_io.h"
#include "femto/memory.h"
#include "femto/plugin.h"
#include "femto/tfilter.h"
#include "femto/time.h"
#include "femto/viz.h"

namespace {

using namespace femto;
using transient_film::BlockStorage;

class TransientFilm;

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
        const size_t e = st_->entry(key(local, bin));
        double* dst = st_->entries[e].rgb;
        dst[0] += w * v.r;
        dst[1] += w * v.g;
        dst[2] += w * v.b;
        if (st_->counts) st_->count[e] += 1.f;
    }
    // Variance needs this sample's value per bin (several contributions may share a bin): w * v
    // into the cube and w * v^2 into the second moment.
    bool totals() const { return st_->variance; }
    void add_total(size_t local, int bin, float w, const Color& v, int n) {
        const size_t e = st_->entry(key(local, bin));
        for (int ch = 0; ch < 3; ++ch) {
            st_->entries[e].rgb[ch] += w * v[ch];
            st_->sq[e * 3 + size_t(ch)] += w * v[ch] * v[ch];
        }
        if (st_->counts) st_->count[e] += float(n);
    }
    static uint64_t key(size_t local, int bin) { return uint64_t(bin) << 32 | uint64_t(local); }

    size_t pixels_;
    std::unique_ptr<BlockStorage> st_;
    mutable bool clean_ = true;  // all sums merged (and the storage emptied) since the last put
    // Film pixel of each block pixel, or SIZE_MAX outside the film: merge looks it up instead
    // of working it out per entry (merge is a hot loop of cube films).
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
        if (const std::string problem = memory_shortfall(total, "the cube and its AOVs");
            !problem.empty())
            props.fail("bins", problem);
        assign_in_huge_pages(cube_, pixels * size_t(grid_.bins) * 3, 0.f);
        map_slot_budget_ = pixels * size_t(grid_.bins) * 3 / 8;
        if (count_enabled_) assign_in_huge_pages(count_, pixels * size_t(grid_.bins), 0.f);
        if (variance_enabled_) assign_in_huge_pages(sq_, cube_.size(), 0.f);
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

    // What a block holds per pixel once every bin of its pixels has an entry (sums, second
    // moment, counts, key and up to four table slots; the vectors' spare capacity aside).
    size_t block_bytes_per_pixel() const override {
        const size_t per_bin = 3 * sizeof(double) * (variance_enabled_ ? 2 : 1) +
                               (count_enabled_ ? sizeof(float) : 0) + sizeof(uint64_t) +
                               4 * sizeof(uint32_t);
        return size_t(grid_.bins) * per_bin;
    }

    /// An empty storage for a block of `pixels` pixels, recycled when possible.
    std::unique_ptr<BlockStorage> acquire_storage(size_t pixels) const {
        std::unique_ptr<BlockStorage> st;
        {
            std::lock_guard<std::mutex> lock(pool_mutex_);
            if (!pool_.empty()) {
                st = std::move(pool_.back());
                pool_.pop_back();
            }
        }
        if (!st) {
            {
                // Room in the pool for every storage there is: a block returns its storage from
                // its destructor, where an allocation that failed would end the program.
                std::lock_guard<std::mutex> lock(pool_mutex_);
                pool_.reserve(storages_ + 1);
                ++storages_;
            }
            st = std::make_unique<BlockStorage>(variance_enabled_, count_enabled_,
                                                size_t(grid_.bins));
        }
        {
            // Maps of every storage together within map_slot_budget_ (with many threads, one
            // map per thread would add up to a good part of the cube): the blocks beyond use the
            // table, which makes the same entries.
            std::lock_guard<std::mutex> lock(pool_mutex_);
            map_slots_ += st->prepare(pixels, map_slot_budget_ - map_slots_);
        }
        return st;
    }
    void release_storage(std::unique_ptr<BlockStorage> st) const {
        std::lock_guard<std::mutex> lock(pool_mutex_);
        pool_.push_back(std::move(st));  // within the capacity acquire_storage() reserved
    }

    void start_pass(uint32_t pass) override { totals_.start(pass); }

    void merge(const FilmBlock& b) override {
        if (merge_pilot(b)) return;
        const auto& block = static_cast<const CubeBlock&>(b);
        BlockStorage& st = *block.st_;
        merge_rejected(block);
        const size_t bins = size_t(grid_.bins);
        const size_t block_pixels = block.pixels_;
        const std::vector<size_t>& dst_of = block.dst_of_local_;
        // The film's entry of block entry e, or SIZE_MAX outside the film.
        auto film_entry = [&](size_t e) {
            const uint64_t key = st.entries[e].key;
            const size_t bin = size_t(key >> 32), local = size_t(key & 0xffffffffu);
            return dst_of[local] == SIZE_MAX ? SIZE_MAX : dst_of[local] * bins + bin;
        };
        // Each (pixel, bin) has one entry, so the order of the adds does not change the cube.
        // Its entries lie anywhere in the cube: ask for them a few entries ahead, and keep where
        // they lie until their turn (a ring of the next kAhead).
        constexpr size_t kAhead = 24;  // the merge took 30 % less time than without
        constexpr size_t kRing = 32;   // a power of two above kAhead
        size_t ahead[kRing];
        const size_t n = st.entries.size();
        for (size_t e = 0; e < std::min(n, kAhead); ++e) ahead[e] = film_entry(e);
        // In the passes that round to nearest, with no AOV, an entry's merge is three float
        // adds: one test here instead of one per channel (a Gaussian filter's pass makes ~13
        // entries a sample for the box filter's 1).
        const bool plain = totals_.rounds_to_nearest() && !variance_enabled_ && !count_enabled_;
        for (size_t e = 0; e < n; ++e) {
            if (e + kAhead < n) {
                const size_t next = film_entry(e + kAhead);
                ahead[(e + kAhead) % kRing] = next;
                if (next != SIZE_MAX) __builtin_prefetch(&cube_[next * 3], 1);
            }
            const size_t at = ahead[e % kRing];
            if (at == SIZE_MAX) continue;
            const double* sums = st.entries[e].rgb;
            if (plain) {
                for (size_t c = 0; c < 3; ++c) cube_[at * 3 + c] += float(sums[c]);
                continue;
            }
            for (size_t c = 0; c < 3; ++c) totals_.add(cube_[at * 3 + c], sums[c], at * 3 + c);
            if (variance_enabled_)
                for (size_t c = 0; c < 3; ++c)
                    totals_.add(sq_[at * 3 + c], st.sq[e * 3 + c], at * 3 + c, ~uint64_t(0));
            if (count_enabled_) totals_.add(count_[at], st.count[e], at, ~uint64_t(0));
        }
        st.clear();
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
    PassTotals totals_;  // how passes add into the float arrays below
    std::vector<float> cube_, count_, sq_;
    mutable std::mutex pool_mutex_;
    mutable std::vector<std::unique_ptr<BlockStorage>> pool_;
    mutable size_t storages_ = 0;  // made so far (the pool's reserved capacity)
    // Block maps' slots allowed in all (4 bytes each: 1/8 of the cube's bytes) and made.
    size_t map_slot_budget_ = 0;
    mutable size_t map_slots_ = 0;
    std::vector<PixelSums> weights_;
};

CubeBlock::CubeBlock(const TransientFilm& film, int x0, int y0, int w, int h)
    : TimeResolvedBlock(film, x0, y0, w, h),
      pixels_(size_t(w_) * size_t(h_)),
      st_(film.acquire_storage(pixels_)),
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
    if (!clean_) {  // never merged (an exception): leave the storage empty for the next block
        st_->clear();
        std::fill(st_->weights.begin(), st_->weights.end(), PixelSums());
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
