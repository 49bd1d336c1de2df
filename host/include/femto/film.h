// femto public API: films, which turn radiance samples into images (and, for transient films,
// into time-resolved images).
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "femto/accumulator.h"
#include "femto/color.h"
#include "femto/kernel.h"
#include "femto/math.h"
#include "femto/object.h"
#include "femto/rfilter.h"

namespace femto {

/// One radiance contribution of a camera sample and its time: the optical path length (time x
/// c, in scene units) of the path that carried it, plus emission time and vertex delays, as
/// PathClock computes it. Steady films ignore the time.
/// A density estimate (photon mapping) may spread its contribution in time by a kernel of its
/// own: time-resolved films then integrate that kernel over their bins in place of their
/// temporal filter's reconstruction (one smoothing, never two).
struct Contribution {
    Color radiance;
    TimeKernel kernel;  ///< none unless a density estimate spreads it
    double time = 0.0;
};

/// A contribution an integrator adds at a film position of its choice (a light path seen by
/// the camera): `radiance` arrives at camera time `time` at film position `pos` (pixels,
/// origin top-left) after a last segment of optical length `sensor_distance` from the sensor
/// (what world-time films subtract and store as depth).
struct Splat {
    Vec2 pos;
    Color radiance;
    uint32_t sample_index = 0;  ///< of the sample that made it (a progressive filter's iteration)
    double time = 0.0;
    double sensor_distance = -1.0;
};

/// The splats of some samples, in the order they were made (the renderer merges them into the
/// film in that order, so renders do not depend on the thread count).
class SplatList {
public:
    void add(const Splat& s) {
        if (!s.radiance.is_black()) items_.push_back(s);
    }
    void clear() { items_.clear(); }
    const std::vector<Splat>& items() const { return items_; }
    /// Index of the sample that adds the next splats, set by the renderer.
    void set_sample_index(uint32_t index) { sample_index_ = index; }
    uint32_t sample_index() const { return sample_index_; }

private:
    std::vector<Splat> items_;
    uint32_t sample_index_ = 0;
};

/// Contributions a film refused, by reason. A NaN, infinite or negative radiance is a bug or a
/// numerical failure upstream; the film drops the whole camera sample (or splat) that carried
/// it, counts each bad contribution here, records the counts in every output's metadata
/// (femto:rejected_*) and warns in the log.
struct RejectedContributions {
    uint64_t nan = 0, infinite = 0, negative = 0;
    uint64_t total() const { return nan + infinite + negative; }
    /// Counts `radiance` when it is bad (NaN first, then infinite, then any channel < 0) and
    /// returns true then.
    bool count(const Color& radiance) {
        const float c[3] = {radiance.r, radiance.g, radiance.b};
        if (std::isnan(c[0]) || std::isnan(c[1]) || std::isnan(c[2])) return ++nan, true;
        if (!radiance.is_finite()) return ++infinite, true;
        if (c[0] < 0 || c[1] < 0 || c[2] < 0) return ++negative, true;
        return false;
    }
    RejectedContributions& operator+=(const RejectedContributions& o) {
        nan += o.nan, infinite += o.infinite, negative += o.negative;
        return *this;
    }
};

/// What the integrator reports for one camera sample.
class ContributionList {
public:
    void add(const Color& radiance, double time, TimeKernel kernel = {}) {
        if (!radiance.is_black()) items_.push_back({radiance, kernel, time});
    }
    void clear() {
        items_.clear();
        sensor_distance_ = -1.0;
    }
    /// Integrator AOVs (arbitrary output variables): one value per channel that the
    /// integrator declares in Integrator::aov_names(), in that order, for this camera sample.
    /// The renderer sizes the list to the declared count and sets every value to 0 before each
    /// camera sample; the integrator sets the values it has (set_aov()). A film that records
    /// AOVs (Film::prepare_aovs()) averages each channel per pixel with the same
    /// reconstruction-filter weights as the radiance. AOVs are not scaled by scale() (not every
    /// channel is a radiance) and splats carry none.
    void reset_aovs(size_t count) { aovs_.assign(count, 0.f); }
    void set_aov(size_t channel, float value) { aovs_[channel] = value; }
    const std::vector<float>& aovs() const { return aovs_; }
    /// Multiplies every contribution by `k` (the renderer applies Sensor::ray_weight()).
    void scale(float k) {
        for (Contribution& c : items_) c.radiance *= k;
    }
    /// Index of this camera sample within its pixel (0, 1, ...), set by the renderer. A
    /// progressive temporal filter uses it as the iteration number of its bandwidth schedule.
    void set_sample_index(uint32_t index) { sample_index_ = index; }
    uint32_t sample_index() const { return sample_index_; }
    const std::vector<Contribution>& items() const { return items_; }
    /// Length of the camera ray's first segment (scene units), set by the integrator at the
    /// first hit; negative when the ray escaped. Films use it for world time (eq. 4.1) and
    /// store it as the per-pixel depth that `femto viz unwarp` needs.
    void set_sensor_distance(double d) { sensor_distance_ = d; }
    double sensor_distance() const { return sensor_distance_; }

    /// Adds radiance at another film position (a bidirectional integrator's light subpath
    /// seen by the camera). Only for integrators whose splats() is true: the renderer then
    /// gives every camera sample a splat list (splat_list()).
    void splat(Vec2 pos, const Color& radiance, double time, double sensor_distance) {
        if (splats_) splats_->add({pos, radiance, sample_index_, time, sensor_distance});
    }
    /// Film position (pixels) of this camera sample, set by the renderer (for integrators that
    /// keep images of their own, e.g. BDPT's per-strategy images).
    void set_film_position(Vec2 pos) { film_position_ = pos; }
    Vec2 film_position() const { return film_position_; }
    /// The list splat() adds to (set by the renderer), or null.
    void set_splat_list(SplatList* splats) { splats_ = splats; }
    SplatList* splat_list() const { return splats_; }

    /// True when this list is one splat, not a camera sample: films add its radiance to the
    /// bins but no filter weight (Film::add_splat_weight() normalises splats).
    void set_is_splat(bool splat) { is_splat_ = splat; }
    bool is_splat() const { return is_splat_; }

private:
    std::vector<Contribution> items_;
    std::vector<float> aovs_;
    double sensor_distance_ = -1.0;
    uint32_t sample_index_ = 0;
    SplatList* splats_ = nullptr;
    bool is_splat_ = false;
    Vec2 film_position_;
};

/// True when every contribution of `sample` is a valid radiance; otherwise counts the bad ones
/// into `rejected` (the film then drops the sample).
inline bool accept_sample(const ContributionList& sample, RejectedContributions& rejected) {
    bool ok = true;
    for (const Contribution& c : sample.items())
        if (rejected.count(c.radiance)) ok = false;
    return ok;
}

/// Metadata recorded into every output file.
struct RenderInfo {
    std::string scene_file;
    std::string integrator;
    std::string femto_version;
    uint64_t seed = 0;
    uint32_t samples_per_pixel = 0;  ///< reached (lower than requested when interrupted)
    uint32_t samples_requested = 0;
    bool write_npy = false;  ///< transient films: also write OUTBASE.npy (float32 [H, W, T, C])
    double render_seconds = 0;
    bool interrupted = false;
    RejectedContributions rejected;  ///< written as femto:rejected_nan / _infinite / _negative
    uint32_t processes = 1;  ///< of a distributed render (written as femto:processes when > 1)
};

/// Calls f(x, y, weight) for every pixel of [x0, x1) x [y0, y1) whose centre lies within
/// the filter radius of film position pos, with the separable filter weight.
template <typename F>
void for_each_filter_pixel(const ReconstructionFilter& filter, Vec2 pos, int x0, int y0, int x1,
                           int y1, F&& f) {
    // floor and ceil of a film coordinate (finite, well inside int's range) by a conversion
    // and a correction: std::floor and std::ceil compile to longer sequences for x86-64's
    // baseline, and a splat runs them per camera sample.
    auto floor_int = [](float x) {
        const int i = int(x);
        return x < float(i) ? i - 1 : i;
    };
    auto ceil_int = [](float x) {
        const int i = int(x);
        return x > float(i) ? i + 1 : i;
    };
    const float r = filter.radius();
    const int xa = std::max(x0, ceil_int(pos.x - 0.5f - r));
    const int xb = std::min(x1 - 1, floor_int(pos.x - 0.5f + r));
    const int ya = std::max(y0, ceil_int(pos.y - 0.5f - r));
    const int yb = std::min(y1 - 1, floor_int(pos.y - 0.5f + r));
    // The filter is separable: each column's weight is evaluated once per sample, not once
    // per pixel (a Gaussian's exp per tap was most of a splat's cost).
    constexpr int kMaxColumns = 64;
    float wx[kMaxColumns];
    const int columns = xb - xa + 1;
    const bool tabulated = columns <= kMaxColumns;
    if (tabulated)
        for (int k = 0; k < columns; ++k) wx[k] = filter.eval(float(xa + k) + 0.5f - pos.x);
    for (int y = ya; y <= yb; ++y) {
        const float wy = filter.eval(float(y) + 0.5f - pos.y);
        if (wy == 0) continue;
        for (int x = xa; x <= xb; ++x) {
            const float w = wy * (tabulated ? wx[x - xa] : filter.eval(float(x) + 0.5f - pos.x));
            if (w != 0) f(x, y, w);
        }
    }
}
/// A rectangle of pixels owned by one worker; accumulates without locks.
class FilmBlock {
public:
    virtual ~FilmBlock() = default;
    /// Splats one camera sample at continuous film position `pos` (pixels, origin top-left).
    virtual void put(Vec2 pos, const ContributionList& sample) = 0;
};

class Film : public Object {
public:
    PluginKind kind() const override { return PluginKind::Film; }

    int width() const { return width_; }
    int height() const { return height_; }
    const ReconstructionFilter& rfilter() const { return *rfilter_; }
    /// Border (in pixels) a block needs around its tile for this film's filter.
    int filter_border() const { return std::max(0, int(std::ceil(rfilter_->radius() - 0.5f))); }

    /// The renderer's tiles are at most this many pixels across (w, h of make_block()): a
    /// film sizing its working memory counts blocks of this size plus the filter's border.
    static constexpr int kMaxTileSize = 32;
    /// Workspace for pixels [x0, x0+w) x [y0, y0+h) plus the filter's border.
    virtual std::unique_ptr<FilmBlock> make_block(int x0, int y0, int w, int h) const = 0;
    /// Adds a finished block into the film. The renderer never merges overlapping blocks
    /// at the same time, so the pixels need no lock; state outside the block's pixels (counts,
    /// statistics) is shared by concurrent merges and needs its own (atomics or a mutex).
    virtual void merge(const FilmBlock& block) = 0;
    /// Called before each render pass (pass 0, 1, ...) starts.
    virtual void start_pass(uint32_t /*pass*/) {}
    /// Samples per pixel of a pilot pass this film needs before rendering (0: none), e.g. for
    /// a temporal filter that estimates its bandwidth from the pilot's arrival times. The
    /// renderer then calls begin_pilot(), runs that pass through make_block()/merge(), and
    /// calls end_pilot().
    virtual uint32_t pilot_samples() const { return 0; }
    /// True when the film can keep the pilot's samples and add them to the image once the
    /// pilot has seen them (the pilot is then the image's first samples, not extra work).
    virtual bool pilot_in_image() const { return false; }
    /// `image_samples` false: the pilot has its own random streams and its samples are not
    /// part of the image. True (only when pilot_in_image()): its samples are the image's
    /// samples [0, n) of every pixel, drawn with the image's streams (the renderer's image
    /// passes then start at n), and with `keep` the film adds them to its image as each tile's
    /// pilot is done (a distributed render keeps them in one process).
    virtual void begin_pilot(bool /*image_samples*/, bool /*keep*/) {}
    virtual void end_pilot() {}
    /// Latest path length (scene units, camera time) this film records; paths beyond it may
    /// stop.
    virtual double max_time() const;
    /// Latest world time (camera time minus the sensor distance) this film records, for a
    /// film in world time; infinite otherwise.
    virtual double max_world_time() const;
    /// Whether integrators may stop paths that can no longer arrive by max_time() /
    /// max_world_time() (TimeWindow::prune); a time-resolved film's `prune_paths`.
    virtual bool prunes_paths() const { return true; }
    /// Bytes a block keeps per pixel of its area, when that is as much as the film keeps per
    /// pixel (a transient film's blocks hold every bin); 0 when blocks are small. The renderer
    /// then picks tiles small enough that blocks in flight stay a small share of the film's
    /// memory (a 16x16 film of 2^20 bins would otherwise hold a second cube in its one block).
    virtual size_t block_bytes_per_pixel() const { return 0; }
    /// Whether pixel row y receives any sample (a streak film records only a few rows);
    /// the renderer skips the others.
    virtual bool row_active(int /*y*/) const { return true; }
    /// Called once before rendering when the integrator splats: `light_only` when it has no
    /// camera samples (a light tracer). A film that cannot take splats throws a SceneError.
    virtual void prepare_splats(bool /*light_only*/) {}
    /// A light tracer's pass of `samples_per_pixel` x pixels light paths is done: adds to every
    /// pixel the filter weight that many camera samples per pixel would have added in
    /// expectation (filter_weight_integral()), so that splats are normalised as camera samples
    /// are. The default throws: the film does not support light tracing.
    virtual void add_splat_weight(double samples_per_pixel);
    /// Called once before rendering when the integrator declares AOV channels (`names`, from
    /// Integrator::aov_names(); never empty): a film that records them keeps one more
    /// filter-weighted average per channel and pixel, fed by ContributionList::aovs(), and
    /// writes them beside its image (hdrfilm: extra named EXR channels). The default throws a
    /// SceneError located at `integrator`: the film records no AOVs.
    virtual void prepare_aovs(const std::vector<std::string>& names, const Object& integrator);
    /// The current image integrated over time: linear RGB, row-major, top row first, normalised
    /// by the reconstruction-filter weights (what name.exr holds for a steady film).
    virtual std::vector<float> steady_image() const = 0;
    /// Writes the outputs for `out_base` (no extension), atomically; returns the paths written.
    virtual std::vector<std::string> write(const std::string& out_base,
                                           const RenderInfo& info) const = 0;

    /// The arrays that hold the film's running totals (pixel sums, weights, counts), which
    /// a distributed render combines across processes before rank 0 writes
    /// (femto/accumulator.h); nothing else of the film may depend on the samples it merged.
    /// The default throws a SceneError: the film cannot take part in a distributed render.
    virtual std::vector<Accumulator> accumulators();

    /// Contributions refused so far (NaN, infinite, negative), over every merged block.
    RejectedContributions rejected() const {
        return {rejected_nan_.load(), rejected_infinite_.load(), rejected_negative_.load()};
    }

    /// `width`, `height` and `rfilter`: what the constructor reads, for the plugin schemas.
    static std::vector<ParamSpec> inherited_params();

protected:
    /// Adds a block's refused contributions (thread-safe: blocks of different tiles merge
    /// concurrently).
    void add_rejected(const RejectedContributions& r) {
        rejected_nan_ += r.nan;
        rejected_infinite_ += r.infinite;
        rejected_negative_ += r.negative;
    }

    /// For each pixel column (`horizontal`) or row, the integral of the reconstruction filter
    /// centred on it over the film's extent: camera samples drawn uniformly over the film give a
    /// pixel (x, y) the expected weight spp x integral_x[x] x integral_y[y].
    std::vector<double> filter_weight_integrals(bool horizontal) const;

    /// Reads `width`, `height` and the <rfilter> child (default `gaussian`); validates sizes.
    explicit Film(const class Properties& props);

    int width_ = 0, height_ = 0;
    std::shared_ptr<ReconstructionFilter> rfilter_;

private:
    std::atomic<uint64_t> rejected_nan_{0}, rejected_infinite_{0}, rejected_negative_{0};
};

}  // namespace femto
