// femto public API: temporal reconstruction (<tfilter> inside a transient or streak film):
// how a contribution at time t is spread over the film's time bins (thesis ch. 5.4-5.5).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "femto/color.h"
#include "femto/film.h"
#include "femto/object.h"
#include "femto/time.h"

namespace femto {

/// One contribution seen by a pilot pass.
struct PilotArrival {
    double time;   ///< recorded time (camera or world, as the film records)
    float energy;  ///< pilot_energy() of its radiance
};

/// A contribution's energy as pilots count it: the mean of its radiance over the colour
/// channels (0 if negative).
inline float pilot_energy(const Color& radiance) {
    return std::max(0.f, (radiance.r + radiance.g + radiance.b) / 3.f);
}

struct BinWeight {
    int bin;
    float weight;  ///< fraction of the contribution that lands in `bin`
};

class TemporalFilter : public Object {
public:
    PluginKind kind() const override { return PluginKind::TemporalFilter; }

    /// Called once by the film before anything else, with its time grid and size in pixels
    /// (pixels are indexed y * width + x).
    virtual void prepare(const TimeGrid& /*grid*/, int /*width*/, int /*height*/) {}

    /// Appends the bins that a unit contribution at time t reaches in pixel `pixel`, with the
    /// integral of the filter's kernel over each bin. `sample_index` is the camera sample's
    /// index within its pixel (0, 1, ...): progressive filters shrink their kernel with it.
    /// The weights sum to the part of the kernel inside the window (for a histogram: 1 when
    /// t is inside it, else nothing). Called concurrently from several threads.
    virtual void splat(const TimeGrid& grid, uint64_t pixel, uint32_t sample_index, double t,
                       std::vector<BinWeight>& out) const = 0;

    /// True when splat() puts a contribution wholly into the bin holding t (a histogram):
    /// films may then bin directly, without a call per contribution.
    virtual bool is_histogram() const { return false; }

    /// Largest distance in time from t that splat() may reach; 0 for a histogram. Films let
    /// paths run this much past the end of the window.
    virtual double max_radius() const { return 0.0; }

    /// Samples per pixel of a pilot pass this filter needs (0: none). After the pilot, the
    /// film calls pilot_pixel() once for every pixel the pilot reached (concurrently for
    /// different pixels, from the merges of the pilot's tiles, while other tiles still render)
    /// and then end_pilot() once.
    virtual uint32_t pilot_samples() const { return 0; }
    /// True when the pilot's samples may be the image's first samples: splat() must then work
    /// for a pixel as soon as its own pilot_pixel() has returned, before end_pilot() (the film
    /// adds a tile's pilot samples to the image right after handing the tile's pixels to the
    /// filter). Renderers fall back to a separate pilot pass where they cannot (integrators
    /// that splat or fix their samples per pass).
    virtual bool pilot_in_image() const { return false; }
    /// Called before the pilot pass: `image_samples` when its samples are the image's first
    /// samples of each pixel (see Film::begin_pilot()). Every process of a distributed render
    /// calls it alike, so that all of them compute the same pilot.
    virtual void begin_pilot(bool /*image_samples*/) {}
    /// The contributions of the `samples` pilot samples (camera samples; 0 for a light pass's
    /// splats, which are not counted) that fell in `pixel`: recorded time and energy (mean
    /// over the colour channels), unordered; the filter may reorder them. A pass whose splats
    /// merge in several batches (light tracers, BDPT's light subpaths) calls it once per batch
    /// that reached the pixel: each call adds to the pixel's pilot.
    virtual void pilot_pixel(uint64_t /*pixel*/, uint32_t /*samples*/,
                             std::vector<PilotArrival>& /*arrivals*/) {}
    virtual void end_pilot() {}
};

/// Reconstructs one camera sample's contributions in time for one film pixel: calls
/// add(bin, value) for every (contribution, bin) pair, value = radiance x bin weight.
/// Returns the energy the filter moved across the window's edges (kernel mass of in-window
/// contributions that fell outside, minus that of outside contributions that fell inside),
/// so that the sum over bins + the returned spill = the sum of the in-window contributions.
template <typename Add>
Color splat_sample(const TemporalFilter& filter, const TimeGrid& grid, uint64_t pixel,
                   const ContributionList& sample, bool world_time, std::vector<BinWeight>& scratch,
                   Add&& add) {
    const bool histogram = filter.is_histogram(), spreads = filter.max_radius() > 0;
    Color spill(0.f);
    for (const Contribution& c : sample.items()) {
        const double t = recorded_time(c.time, sample.sensor_distance(), world_time);
        if (c.kernel.spreads()) {  // the estimate's own kernel replaces the filter
            const double inside =
                integrate_over_bins(grid, c.kernel.shape, t, c.kernel.half_width,
                                    [&](int bin, double w) { add(bin, c.radiance * float(w)); });
            spill += c.radiance * float((grid.contains(t) ? 1.0 : 0.0) - inside);
            continue;
        }
        if (histogram) {
            const int bin = grid.bin_of(t);
            if (bin >= 0) add(bin, c.radiance);
            continue;
        }
        scratch.clear();
        filter.splat(grid, pixel, sample.sample_index(), t, scratch);
        float inside = 0.f;
        for (const BinWeight& bw : scratch) {
            add(bw.bin, c.radiance * bw.weight);
            inside += bw.weight;
        }
        if (spreads) spill += c.radiance * ((grid.contains(t) ? 1.f : 0.f) - inside);
    }
    return spill;
}

/// Film block for a temporal filter's pilot pass: keeps, for every pixel of its tile, the
/// arrivals (time, energy) of the contributions of the samples that fall in the pixel, and
/// hands them to the filter in deliver() (call it from the film's merge()). In a pilot that is
/// part of the image it also keeps the samples themselves, and deliver() then puts them into
/// `image`, the film's own block for the tile, and hands that block back for merging.
class PilotBlock final : public FilmBlock {
public:
    PilotBlock(int x0, int y0, int w, int h, int film_width, bool world_time,
               std::unique_ptr<FilmBlock> image = nullptr);
    void put(Vec2 pos, const ContributionList& sample) override;
    /// Hands every pixel's arrivals to the filter; then, in a pilot in the image, puts the
    /// kept samples into the image block (in the order they came) and returns that block.
    std::unique_ptr<FilmBlock> deliver(TemporalFilter& filter) const;

private:
    /// Index in the tile of the pixel that holds `pos` (no reconstruction filter: the pilot
    /// only measures how arrivals spread in time); SIZE_MAX outside the tile.
    size_t local_pixel(Vec2 pos) const;
    void add_arrivals(size_t local, const Contribution* first, size_t count,
                      double sensor_distance) const;

    struct KeptSample {  // a sample of a pilot in the image, its contributions in kept_
        Vec2 pos;
        uint32_t sample_index, first, count;
        double sensor_distance;
        bool splat;
    };
    int x0_, y0_, w_, h_, film_width_;
    bool world_time_;
    mutable std::vector<std::vector<PilotArrival>> arrivals_;  // [h_][w_]
    std::vector<uint32_t> samples_;                            // camera samples per pixel
    mutable std::unique_ptr<FilmBlock> image_;
    std::vector<KeptSample> kept_samples_;
    std::vector<Contribution> kept_;
};

/// The sums a time-resolved film keeps per pixel next to its bins (doubles: they add up many
/// small weights). The filter weights normalise the bins; the depth is what `femto viz unwarp`
/// needs; the spill is what the temporal filter moved across the window's edges.
struct PixelSums {
    double weight = 0;        ///< sum of the filter weights w of all samples
    double weight2 = 0;       ///< sum of w^2 (effective sample count: weight^2 / weight2)
    double depth_sum = 0;     ///< sum of w * sensor distance over the samples that hit something
    double depth_weight = 0;  ///< sum of w over those samples
    double spill[3] = {0, 0, 0};  ///< sum of w * energy moved out of the window (splat_sample)

    PixelSums& operator+=(const PixelSums& o) {
        weight += o.weight;
        weight2 += o.weight2;
        depth_sum += o.depth_sum;
        depth_weight += o.depth_weight;
        for (int c = 0; c < 3; ++c) spill[c] += o.spill[c];
        return *this;
    }
    /// True when no sample has added anything (filter weight, depth or spill) to the pixel.
    bool empty() const {
        return weight == 0 && depth_weight == 0 && spill[0] == 0 && spill[1] == 0 && spill[2] == 0;
    }
    /// The filter-weighted mean sensor distance of the samples that hit something; -1 where
    /// none did.
    float depth() const { return depth_weight > 0 ? float(depth_sum / depth_weight) : -1.f; }
};

class TimeResolvedFilm;

/// Base of the blocks of time-resolved films: the splat they share. A block covers a tile plus
/// the reconstruction filter's border, pixels [x0(), x0() + w()) x [y0(), y0() + h()); its
/// subclass keeps only the storage and calls splat() from put().
class TimeResolvedBlock : public FilmBlock {
public:
    /// Contributions this block refused (a NaN, infinite or negative radiance; the whole
    /// sample that carried one is dropped).
    const RejectedContributions& rejected() const { return rejected_; }
    /// Arrivals (camera-sample contributions with light) this block saw, the earliest and
    /// latest recorded time among them, and how many fell in the film's window.
    struct Arrivals {
        uint64_t count = 0, inside = 0;
        double earliest = std::numeric_limits<double>::infinity();
        double latest = -std::numeric_limits<double>::infinity();
        void add(double t, bool in_window) {
            ++count;
            inside += in_window ? 1 : 0;
            earliest = std::min(earliest, t);
            latest = std::max(latest, t);
        }
        Arrivals& operator+=(const Arrivals& o) {
            count += o.count;
            inside += o.inside;
            earliest = std::min(earliest, o.earliest);
            latest = std::max(latest, o.latest);
            return *this;
        }
    };
    const Arrivals& arrivals() const { return arrivals_; }
    int x0() const { return x0_; }
    int y0() const { return y0_; }
    int w() const { return w_; }
    int h() const { return h_; }

protected:
    /// The block of tile [x0, x0 + w) x [y0, y0 + h), grown by the film's filter border.
    TimeResolvedBlock(const TimeResolvedFilm& film, int x0, int y0, int w, int h);

    /// Splats one camera sample at film position `pos`: for every block pixel (x, y) within the
    /// reconstruction filter's reach (weight w) that `storage` holds, adds w (unless the sample
    /// is a splat: ContributionList::is_splat()) and the sample's sensor distance when it hit
    /// something to the pixel's PixelSums and w x the temporal
    /// filter's bin values (splat_sample) to its bins. The temporal filter spreads the sample
    /// as its home pixel (the one `pos` lies in) asks, in every pixel it reaches: a pixel's
    /// bandwidth is then known once its own pilot is, whatever its neighbours'. `Storage` provides
    ///     size_t slot(int x, int y);        // pixel (x, y) in the storage; SIZE_MAX: not held
    ///     PixelSums& sums(size_t slot);
    ///     void add(size_t slot, int bin, float w, const Color& v);   // bin += w * v
    /// and, to receive each bin once per sample with the sum v of the sample's n values in it
    /// (e.g. for a second moment w * v^2), instead of add() per (contribution, bin) pair:
    ///     bool totals() const;
    ///     void add_total(size_t slot, int bin, float w, const Color& v, int n);
    /// A sample with a NaN, infinite or negative radiance adds nothing; its bad contributions
    /// are counted in rejected().
    template <typename Storage>
    void splat(Vec2 pos, const ContributionList& sample, Storage& storage);

    const TimeResolvedFilm& film_;
    int x0_, y0_, w_, h_;

private:
    template <typename Storage>
    Color splat_totals(uint64_t pixel, size_t slot, float w, const ContributionList& sample,
                       Storage& storage);

    std::vector<BinWeight> scratch_;
    std::vector<std::pair<int, Color>> sample_bins_;  // one sample's (bin, value) pairs
    RejectedContributions rejected_;
    Arrivals arrivals_;
};

/// Base of films that record time (`transient`, `streak`): reads the time grid (`start`,
/// `bin_width`, `bins`, or their `*_ps` forms), `world_time`, `exposure` and the nested
/// <tfilter>, prepares the filter for the film's pixels, and runs the filter's pilot pass.
/// A subclass makes its own blocks (derived from TimeResolvedBlock) and merges them, after
/// giving the pilot pass its turn:
///     if (auto b = make_pilot_block(x0, y0, w, h)) return b;   // in make_block()
///     if (merge_pilot(block)) return;                           // in merge()
///     merge_rejected(static_cast<const MyBlock&>(block));      // then, in merge()
/// and calls warn_empty_window() when it writes. (In a pilot in the image, make_pilot_block()
/// calls make_block() again for the tile's own block, and merge_pilot() calls merge() with it.)
class TimeResolvedFilm : public Film {
public:
    uint32_t pilot_samples() const override { return tfilter_->pilot_samples(); }
    bool pilot_in_image() const override { return tfilter_->pilot_in_image(); }
    void begin_pilot(bool image_samples, bool keep) override {
        pilot_ = true;
        pilot_into_image_ = image_samples && keep;
        tfilter_->begin_pilot(image_samples);
    }
    void end_pilot() override;
    /// The grid's end plus the filter's reach in camera time; unbounded in world time (the
    /// sensor segment is subtracted after the path ends, so the integrator cannot cut it).
    double max_time() const override;
    double max_world_time() const override;
    bool prunes_paths() const override { return prune_paths_; }

    const TimeGrid& grid() const { return grid_; }
    const TemporalFilter& tfilter() const { return *tfilter_; }
    /// True when the film records world time (the sensor segment removed, eq. 4.1).
    bool world_time() const { return grid_.frame == TimeFrame::World; }

    /// Film's parameters, the time window (time_grid_params()), `world_time`, `exposure` and
    /// the <tfilter> child (default `histogram`): what the constructor reads.
    static std::vector<ParamSpec> inherited_params();

protected:
    explicit TimeResolvedFilm(const Properties& props);
    /// During the pilot pass, the block that collects arrivals for the filter; else null.
    std::unique_ptr<FilmBlock> make_pilot_block(int x0, int y0, int w, int h) const;
    /// During the pilot pass, hands the block's arrivals to the filter and returns true.
    bool merge_pilot(const FilmBlock& block);
    /// Adds the block's refused contributions (and its arrivals) to the film's.
    void merge_rejected(const TimeResolvedBlock& block) {
        add_rejected(block.rejected());
        // Blocks of tiles that do not overlap merge at the same time; these few sums are the
        // only state they share (a static lock: the class layout is part of the plugin ABI).
        static std::mutex arrivals_mutex;
        std::lock_guard<std::mutex> lock(arrivals_mutex);
        arrivals_ += block.arrivals();
    }
    /// Film::add_splat_weight() for pixel sums `sums` kept row by row (width() per row): of
    /// every row, or of the pixel rows `rows` (sums row i is pixel row rows[i]).
    void add_expected_weight(double samples_per_pixel, std::vector<PixelSums>& sums,
                             const std::vector<int>* rows = nullptr) const;
    /// Logs a warning when no light arrived within the time window (with the times it arrived
    /// at instead).
    void warn_empty_window() const;
    /// The accumulators of the base (the arrival statistics of warn_empty_window()) followed
    /// by the subclass's `totals`: what a subclass returns from accumulators().
    std::vector<Accumulator> with_window_accumulators(std::vector<Accumulator> totals) {
        totals.push_back(Accumulator::of_counts(&arrivals_.count, 1));
        totals.push_back(Accumulator::of_counts(&arrivals_.inside, 1));
        totals.push_back(Accumulator::of_doubles(&arrivals_.earliest, 1, Accumulator::Op::Min));
        totals.push_back(Accumulator::of_doubles(&arrivals_.latest, 1, Accumulator::Op::Max));
        return totals;
    }

    TimeGrid grid_;       ///< its frame is camera or world time (`world_time`)
    float exposure_ = 0;  ///< preview exposure in stops (0: automatic)
    std::shared_ptr<TemporalFilter> tfilter_;

private:
    bool pilot_ = false;  // between begin_pilot() and end_pilot()
    bool pilot_into_image_ = false;
    bool prune_paths_ = true;
    TimeResolvedBlock::Arrivals arrivals_;
};

inline TimeResolvedBlock::TimeResolvedBlock(const TimeResolvedFilm& film, int x0, int y0, int w,
                                            int h)
    : film_(film),
      x0_(x0 - film.filter_border()),
      y0_(y0 - film.filter_border()),
      w_(w + 2 * film.filter_border()),
      h_(h + 2 * film.filter_border()) {}

template <typename Storage>
void TimeResolvedBlock::splat(Vec2 pos, const ContributionList& sample, Storage& storage) {
    const double sensor = sample.sensor_distance();
    const TemporalFilter& tfilter = film_.tfilter();
    const TimeGrid& grid = film_.grid();
    const bool world_time = film_.world_time();
    bool totals = false;
    if constexpr (requires { storage.add_total(0, 0, 1.f, Color(), 1); }) totals = storage.totals();
    // One walk over the contributions before the pixels: it checks them (a bad one drops the
    // whole sample), notes their arrivals (for the empty-window warning) and, where each goes
    // whole into one bin (a histogram, no estimate's own kernel), finds the bins once for all
    // the pixels the filter reaches (the walks per pixel were ~a third of a cube film's put).
    // splat_totals() uses sample_bins_ as its own scratch, so totals go the general way.
    bool binned = tfilter.is_histogram() && !totals;
    sample_bins_.clear();
    Arrivals arrivals;
    bool valid = true;
    for (const Contribution& c : sample.items()) {
        if (rejected_.count(c.radiance)) {
            valid = false;
            continue;
        }
        const double t = recorded_time(c.time, sensor, world_time);
        const bool inside = grid.contains(t);
        arrivals.add(t, inside);
        if (c.kernel.spreads())
            binned = false;
        else if (binned && inside)
            sample_bins_.push_back({grid.bin_of(t), c.radiance});
    }
    if (!valid) return;
    arrivals_ += arrivals;
    // int() truncates where floor rounds down, which differs only below 0, clamped to 0 either
    // way (std::floor is a library call for x86-64's baseline, two per camera sample).
    const int home_x = std::clamp(int(pos.x), 0, film_.width() - 1),
              home_y = std::clamp(int(pos.y), 0, film_.height() - 1);
    const uint64_t pixel = uint64_t(home_y) * uint64_t(film_.width()) + uint64_t(home_x);
    for_each_filter_pixel(
        film_.rfilter(), pos, x0_, y0_, x0_ + w_, y0_ + h_, [&](int x, int y, float w) {
            const size_t slot = storage.slot(x, y);
            if (slot == SIZE_MAX) return;
            PixelSums& sums = storage.sums(slot);
            if (!sample.is_splat()) {  // splats are normalised by Film::add_splat_weight()
                sums.weight += w;
                sums.weight2 += double(w) * w;
            }
            if (sensor >= 0) {
                sums.depth_sum += w * sensor;
                sums.depth_weight += w;
            }
            if (binned) {  // a histogram moves nothing across the window's edges: no spill
                for (const auto& [bin, v] : sample_bins_) storage.add(slot, bin, w, v);
                return;
            }
            Color spill;
            if constexpr (requires { storage.add_total(slot, 0, w, spill, 1); }) {
                if (totals) spill = splat_totals(pixel, slot, w, sample, storage);
            }
            if (!totals)
                spill =
                    splat_sample(tfilter, grid, pixel, sample, world_time, scratch_,
                                 [&](int bin, const Color& v) { storage.add(slot, bin, w, v); });
            if (!spill.is_black())  // a histogram's never is: it moves nothing across the edges
                for (int c = 0; c < 3; ++c) sums.spill[c] += double(w) * spill[c];
        });
}

template <typename Storage>
Color TimeResolvedBlock::splat_totals(uint64_t pixel, size_t slot, float w,
                                      const ContributionList& sample, Storage& storage) {
    sample_bins_.clear();
    const Color spill = splat_sample(film_.tfilter(), film_.grid(), pixel, sample,
                                     film_.world_time(), scratch_, [&](int bin, const Color& v) {
                                         sample_bins_.push_back({bin, v});
                                     });
    std::sort(sample_bins_.begin(), sample_bins_.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    for (size_t i = 0; i < sample_bins_.size();) {
        const int bin = sample_bins_[i].first;
        Color v;
        int n = 0;
        for (; i < sample_bins_.size() && sample_bins_[i].first == bin; ++i, ++n)
            v += sample_bins_[i].second;
        storage.add_total(slot, bin, w, v, n);
    }
    return spill;
}

}  // namespace femto
