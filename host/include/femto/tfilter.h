// femto public API: temporal reconstruction (<tfilter> inside a transient or streak film):
// how a contribution at time t is spread over the film's time bins (thesis ch. 5.4-5.5).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "femto/color.h"
#include "femto/film.h"
#include "femto/object.h"
#include "femto/time.h"

namespace femto {

/// One contribution seen by a pilot pass.
struct PilotArrival {
    double time;   ///< recorded time (camera or world, as the film records)
    float energy;  ///< mean of its radiance over the colour channels
};

struct BinWeight {
    int bin;
    float weight;  ///< fraction of the contribution that lands in `bin`
};

class TemporalFilter : public Object {
public:
    PluginKind kind() const override { return PluginKind::TemporalFilter; }

    /// Called once by the film before anything else, with its time grid and pixel count
    /// (pixels are indexed y * width + x).
    virtual void prepare(const TimeGrid& /*grid*/, uint64_t /*pixels*/) {}

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
    /// different pixels) and then end_pilot() once.
    virtual uint32_t pilot_samples() const { return 0; }
    /// The contributions of the pilot samples in `pixel`: recorded time and energy (mean over
    /// the colour channels), unordered; the filter may reorder them.
    virtual void pilot_pixel(uint64_t /*pixel*/, std::vector<PilotArrival>& /*arrivals*/) {}
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
    if (filter.is_histogram()) {
        for (const Contribution& c : sample.items()) {
            const int bin =
                grid.bin_of(recorded_time(c.path_length, sample.sensor_distance(), world_time));
            if (bin >= 0) add(bin, c.radiance);
        }
        return Color(0.f);
    }
    const bool spreads = filter.max_radius() > 0;
    Color spill(0.f);
    for (const Contribution& c : sample.items()) {
        const double t = recorded_time(c.path_length, sample.sensor_distance(), world_time);
        scratch.clear();
        filter.splat(grid, pixel, sample.sample_index(), t, scratch);
        float inside = 0.f;
        for (const BinWeight& bw : scratch) {
            add(bw.bin, c.radiance * bw.weight);
            inside += bw.weight;
        }
        if (spreads) spill += c.radiance * ((grid.bin_of(t) >= 0 ? 1.f : 0.f) - inside);
    }
    return spill;
}

/// Film block for a temporal filter's pilot pass: keeps, for every pixel of its tile, the
/// arrivals (time, energy) of the contributions of the samples that fall in the pixel, and
/// hands them to the filter in deliver() (call it from the film's merge()).
class PilotBlock final : public FilmBlock {
public:
    PilotBlock(int x0, int y0, int w, int h, int film_width, bool world_time);
    void put(Vec2 pos, const ContributionList& sample) override;
    void deliver(TemporalFilter& filter) const;

private:
    int x0_, y0_, w_, h_, film_width_;
    bool world_time_;
    mutable std::vector<std::vector<PilotArrival>> arrivals_;  // [h_][w_]
};

/// Base of films that record time (`transient`, `streak`): reads the time grid (`start`,
/// `bin_width`, `bins`, or their `*_ps` forms), `world_time`, `exposure` and the nested
/// <tfilter>, prepares the filter for the film's pixels, and runs the filter's pilot pass.
/// A subclass makes its own blocks and merges them, after giving the pilot pass its turn:
///     if (auto b = make_pilot_block(x0, y0, w, h)) return b;   // in make_block()
///     if (merge_pilot(block)) return;                           // in merge()
class TimeResolvedFilm : public Film {
public:
    uint32_t pilot_samples() const override { return tfilter_->pilot_samples(); }
    void begin_pilot() override { pilot_ = true; }
    void end_pilot() override;
    /// The grid's end plus the filter's reach in camera time; unbounded in world time (the
    /// sensor segment is subtracted after the path ends, so the integrator cannot cut it).
    double max_path_length() const override;

    const TimeGrid& grid() const { return grid_; }
    const TemporalFilter& tfilter() const { return *tfilter_; }
    /// True when the film records world time (the sensor segment removed, eq. 4.1).
    bool world_time() const { return world_time_; }

    /// Film's parameters, the time window (time_grid_params()), `world_time`, `exposure` and
    /// the <tfilter> child (default `histogram`): what the constructor reads.
    static std::vector<ParamSpec> inherited_params();

protected:
    explicit TimeResolvedFilm(const Properties& props);
    /// During the pilot pass, the block that collects arrivals for the filter; else null.
    std::unique_ptr<FilmBlock> make_pilot_block(int x0, int y0, int w, int h) const;
    /// During the pilot pass, hands the block's arrivals to the filter and returns true.
    bool merge_pilot(const FilmBlock& block);

    TimeGrid grid_;
    bool world_time_ = false;
    float exposure_ = 0;  ///< preview exposure in stops (0: automatic)
    std::shared_ptr<TemporalFilter> tfilter_;

private:
    bool pilot_ = false;  // between begin_pilot() and end_pilot()
};

}  // namespace femto
