// Progressive kernel density estimation in time (thesis ch. 5.5, eq. 5.17, appendix 5.A).
//
// Each contribution at time t is spread over the bins by a normalised kernel K_T of
// half-width ("bandwidth") T, integrated exactly over every bin it overlaps, so the bins of a
// pixel still sum to its steady value (up to the kernel mass that falls outside the window;
// the films account for it). The estimate is progressive: the j-th camera sample of every
// pixel (j = 1, 2, ...) uses T_j, shrinking as T_{j+1} / T_j = (j + alpha) / (j + 1), i.e.
// T_j = T_1 / (j alpha B(alpha, j)) (eq. 5.47). The film's average over samples is then the
// average of the per-iteration estimates, whose variance falls as O(n^-alpha) and squared
// bias as O(n^-4(1-alpha)); alpha = 4/5 balances them (AMSE O(n^-4/5), eq. 5.52).
// Iterations are counted per pixel sample, not per render pass, so the result does not depend
// on how the renderer groups samples into passes or threads.
//
// T_1 is `bandwidth` when given. Otherwise it adapts to where light arrives (ch. 5.7 uses 40
// nearest neighbours): a pilot of `pilot_spp` samples per pixel records each pixel's arrivals
// (time, energy), and a contribution at time t gets T_1 = the distance from t to its k-th
// nearest pilot arrival in its home pixel (`k_neighbors`, counted among pilot_spp samples'
// arrivals), neighbours counted by energy: the pixel keeps 128 quantiles of
// its energy-weighted arrival times, and k of n arrivals becomes k * 128 / n quantiles. A
// bright peak thus keeps a narrow kernel even when few samples carry it (a directly seen lamp),
// while the dim indirect tail is smoothed widely (counting arrivals instead smeared such
// peaks: bench/README.md). Each kernel is still normalised, so energy is kept (a
// "sample-point" adaptive estimate). T_1 is clamped to [half a bin, 1/8 of the window].
// Pixels with fewer than two pilot arrivals use the median bandwidth of the others. A pixel's
// pilot may arrive in batches (a light pass's splats merge in waves): each adds to the quantiles
// kept, which stand for their share of the energy seen before.
//
// By default the pilot's samples are the image's first pilot_spp samples (`pilot_in_image`):
// each tile keeps them until its pixels' bandwidths are set, then adds them to the image, so
// the pilot costs no extra paths (a separate pilot of 64 spp took 0.71 of a 16-spp render:
// bench/README.md). A render of fewer samples takes them all as its pilot, with k scaled to
// them. Before the last tile's pilot is done the median fallback is unknown; the few pilot
// samples of pixels with fewer than two arrivals are binned as a histogram would. The
// bandwidth is chosen from the samples it then spreads (a bright one fills many of its pixel's
// energy quantiles and narrows its own kernel): bench/README.md measured no effect on the
// errors from 64 samples on, and rougher per-pixel profiles in renders of fewer.
//
// With `pilot_radius` r > 0 the pilot is shared across pixels: each pixel's arrivals are
// pooled with those of its neighbours within r pixels before its quantiles are taken, so a
// short pilot (8 spp over 3x3: 72 samples' arrivals) costs a fraction of a 64-spp pilot of the
// pixel's own. It is off by default: pooling widens the spread of times the nearest neighbours
// see (neighbours' paths differ in length), and bench/README.md measured the trade (faster
// errors at small budgets, worse cube or frame errors at large ones, depending on k).

#include "femto/kernel.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <utility>
#include <vector>

#include "femto/plugin.h"
#include "femto/tfilter.h"

namespace {

using namespace femto;

class KernelFilter final : public TemporalFilter {
public:
    explicit KernelFilter(const Properties& props) {
        shape_ = read_kernel_shape(props, "kernel", "perlin");
        alpha_ = props.get_float("alpha", 0.8);
        if (!(alpha_ > 0.0 && alpha_ <= 1.0))
            props.fail("alpha", "alpha must lie in (0, 1] (1 keeps the bandwidth fixed)");
        if (props.has("bandwidth")) {
            fixed_bandwidth_ = props.get_float("bandwidth");
            if (!(fixed_bandwidth_ > 0.0) || !std::isfinite(fixed_bandwidth_))
                props.fail("bandwidth", "bandwidth must be positive and finite (scene units)");
        }
        const int64_t k = props.get_int("k_neighbors", 40);
        if (k < 1 || k > 100000) props.fail("k_neighbors", "k_neighbors must lie in [1, 100000]");
        k_neighbors_ = size_t(k);
        const int64_t pilot = props.get_int("pilot_spp", 64);
        if (pilot < 1 || pilot > 65536) props.fail("pilot_spp", "pilot_spp must lie in [1, 65536]");
        pilot_spp_ = uint32_t(pilot);
        const int64_t radius = props.get_int("pilot_radius", 0);
        if (radius < 0 || radius > 16)
            props.fail("pilot_radius", "pilot_radius must lie in [0, 16]");
        pilot_radius_ = int(radius);
        pilot_in_image_ = props.get_bool("pilot_in_image", pilot_radius_ == 0);
        if (pilot_in_image_ && pilot_radius_ > 0)
            props.fail("pilot_in_image",
                       "a pilot in the image cannot be pooled (pilot_radius): a pixel's bandwidth "
                       "is needed before its neighbours' pilots have run");
        for (const char* pilot_param :
             {"k_neighbors", "pilot_spp", "pilot_radius", "pilot_in_image"})
            if (fixed_bandwidth_ > 0 && props.has(pilot_param))
                props.fail(pilot_param,
                           "k_neighbors, pilot_spp, pilot_radius and pilot_in_image choose the "
                           "bandwidth from a "
                           "pilot pass; they cannot be combined with a given bandwidth");
        schedule_.resize(4096);
        for (size_t j = 0; j < schedule_.size(); ++j) schedule_[j] = closed_form(uint32_t(j));
    }

    void prepare(const TimeGrid& grid, int width, int height) override {
        grid_ = grid;
        width_ = width, height_ = height;
        const size_t pixels = size_t(width) * size_t(height);
        if (fixed_bandwidth_ > 0) {
            max_t1_ = fixed_bandwidth_;
        } else {
            pilot_.assign(size_t(pixels), PixelPilot());
            arrivals_.assign(size_t(pixels) * kMaxArrivals, 0.f);
            max_t1_ = 0.0;  // until the pilot: see begin_pilot()
        }
    }

    /// T_j / T_1 for sample index j - 1: the product of eq. 5.47 in closed form.
    double closed_form(uint32_t sample_index) const {
        return progressive_shrink(alpha_, sample_index);
    }
    double shrink(uint32_t sample_index) const {
        return sample_index < schedule_.size() ? schedule_[sample_index]
                                               : closed_form(sample_index);
    }

    /// T_1 for a contribution at time t in `pixel` (0 before the pilot has run).
    double initial_bandwidth(uint64_t pixel, double t) const {
        if (fixed_bandwidth_ > 0) return fixed_bandwidth_;
        if (pixel >= pilot_.size()) return 0.0;
        const PixelPilot& pp = pilot_[size_t(pixel)];
        if (pp.count < 2) return pp.fallback;
        const float* a = &arrivals_[size_t(pixel) * kMaxArrivals];
        const size_t n = pp.count, k = pp.k;
        // The k nearest arrivals form a run of k consecutive sorted arrivals next to t.
        const size_t p = size_t(std::lower_bound(a, a + n, float(t)) - a);
        double best = std::numeric_limits<double>::infinity();
        const size_t l0 = p >= k ? p - k : 0, l1 = std::min(p, n - k);
        for (size_t l = l0; l <= l1; ++l)
            best = std::min(best, std::max(t - double(a[l]), double(a[l + k - 1]) - t));
        return clamp_bandwidth(best);
    }

    void splat(const TimeGrid& grid, uint64_t pixel, uint32_t sample_index, double t,
               std::vector<BinWeight>& out) const override {
        const double T = initial_bandwidth(pixel, t) * shrink(sample_index);
        if (!(T > 0.0)) {  // no bandwidth known (pilot not run for this pixel): a histogram
            const int bin = grid.bin_of(t);
            if (bin >= 0) out.push_back({bin, 1.f});
            return;
        }
        integrate_over_bins(grid, shape_, t, T, [&](int bin, double w) {
            out.push_back({bin, float(w)});
        });
    }

    double max_radius() const override { return max_t1_; }

    uint32_t pilot_samples() const override { return fixed_bandwidth_ > 0 ? 0 : pilot_spp_; }
    bool pilot_in_image() const override { return pilot_in_image_; }
    void begin_pilot(bool image_samples) override {
        // A separate pilot's paths stop at the window's end; a pilot of image samples is
        // spread as the image is, so its paths run as far.
        if (fixed_bandwidth_ <= 0)
            max_t1_ = image_samples ? clamp_bandwidth(std::numeric_limits<double>::infinity()) : 0;
    }

    void pilot_pixel(uint64_t pixel, uint32_t samples,
                     std::vector<PilotArrival>& arrivals) override {
        if (pixel >= pilot_.size()) return;
        PixelPilot& pp = pilot_[size_t(pixel)];
        // Another batch of the same pixel's pilot (a light pass's splats merge in waves): the
        // quantiles kept so far join it, each standing for its share of their energy.
        const size_t new_arrivals = arrivals.size();
        if (pp.count > 0) {
            const float* kept = &arrivals_[size_t(pixel) * kMaxArrivals];
            for (uint32_t q = 0; q < pp.count; ++q)
                arrivals.push_back({double(kept[q]), pp.energy / float(pp.count)});
            samples += pp.samples;
        }
        if (arrivals.size() < 2) return;
        std::sort(arrivals.begin(), arrivals.end(),
                  [](const PilotArrival& a, const PilotArrival& b) { return a.time < b.time; });
        const size_t n = arrivals.size(), m = std::min(n, kMaxArrivals);
        double total = 0;
        for (const PilotArrival& a : arrivals) total += double(a.energy);
        pp.seen = uint32_t(std::min<size_t>(new_arrivals + pp.seen, UINT32_MAX));
        pp.samples = samples;
        pp.energy = float(total);
        float* kept = &arrivals_[size_t(pixel) * kMaxArrivals];
        if (total > 0) {
            // m quantiles of the energy-weighted arrival times: where the pixel's energy
            // arrives, not merely where its samples do (a bright, sparse peak stays sharp).
            double below = 0;
            size_t i = 0;
            for (size_t q = 0; q < m; ++q) {
                const double level = (double(q) + 0.5) / double(m) * total;
                while (i + 1 < n && below + double(arrivals[i].energy) < level)
                    below += double(arrivals[i++].energy);
                kept[q] = float(arrivals[i].time);
            }
        } else {
            for (size_t q = 0; q < m; ++q)  // evenly spaced order statistics
                kept[q] = float(arrivals[m == n ? q : (q * (n - 1)) / (m - 1)].time);
        }
        pp.count = uint32_t(m);
        // k of n neighbours, scaled to the m kept; at least 1 and at most m - 1. k counts among
        // the arrivals of pilot_spp samples: a pixel that had fewer (a short render's pilot in
        // the image, adaptive sampling) takes the same share of its arrivals.
        const double k = samples > 0 && samples < pilot_spp_
                             ? double(k_neighbors_) * double(samples) / double(pilot_spp_)
                             : double(k_neighbors_);
        pp.k = uint32_t(
            std::clamp<size_t>(size_t(std::lround(k * double(m) / double(pp.seen))), 1, m - 1));
    }

    void end_pilot() override {
        if (pilot_radius_ > 0) pool_neighbours();
        // Fallback for pixels without pilot arrivals: the median over pixels of the bandwidth
        // at their median arrival.
        std::vector<double> typical;
        for (size_t p = 0; p < pilot_.size(); ++p)
            if (pilot_[p].count >= 2)
                typical.push_back(initial_bandwidth(
                    p, double(arrivals_[p * kMaxArrivals + pilot_[p].count / 2])));
        double fallback = clamp_bandwidth(std::numeric_limits<double>::infinity());
        if (!typical.empty()) {
            std::nth_element(typical.begin(), typical.begin() + ptrdiff_t(typical.size() / 2),
                             typical.end());
            fallback = typical[typical.size() / 2];
        }
        for (PixelPilot& pp : pilot_) pp.fallback = float(fallback);
        max_t1_ = clamp_bandwidth(std::numeric_limits<double>::infinity());
    }

private:
    static constexpr size_t kMaxArrivals = 128;
    struct PixelPilot {
        uint32_t count = 0;    // arrivals kept (sorted) in arrivals_
        uint32_t k = 0;        // neighbours counted among them
        uint32_t seen = 0;     // arrivals the pilot recorded (count keeps at most 128 of them)
        float energy = 0;      // their total energy
        float fallback = 0;    // T_1 when the pixel had fewer than two arrivals
        uint32_t samples = 0;  // camera samples the pilot counted (0: splats only)
    };

    // Replaces every pixel's kept quantiles by those of the arrivals of the pixels within
    // pilot_radius_ (clipped at the image's edges). Each pixel kept m quantiles of equal
    // energy, so a quantile of pixel q stands for energy_q / m_q of the pool (or, where the pool
    // holds no energy, seen_q / m_q arrivals); merged in time order, they give the pool's own m
    // quantiles, and k counts among the pool's arrivals.
    void pool_neighbours() {
        std::vector<float> pooled(arrivals_.size());
        std::vector<PixelPilot> pooled_pilot(pilot_.size());
        tbb::parallel_for(0, height_, [&](int y) {
            for (int x = 0; x < width_; ++x) {
                const size_t p = size_t(y) * size_t(width_) + size_t(x);
                pool_pixel(x, y, &pooled[p * kMaxArrivals], pooled_pilot[p]);
            }
        });
        arrivals_.swap(pooled);
        pilot_.swap(pooled_pilot);
    }

    void pool_pixel(int x, int y, float* out, PixelPilot& result) const {
        struct Source {
            const float* times;
            const PixelPilot* pilot;
            double weight = 0;  // of each of its quantiles
        };
        std::vector<Source> sources;
        double energy = 0, seen = 0;
        size_t kept = 0;
        const int r = pilot_radius_;
        for (int yy = std::max(0, y - r); yy <= std::min(height_ - 1, y + r); ++yy)
            for (int xx = std::max(0, x - r); xx <= std::min(width_ - 1, x + r); ++xx) {
                const size_t q = size_t(yy) * size_t(width_) + size_t(xx);
                if (pilot_[q].count < 2) continue;
                sources.push_back({&arrivals_[q * kMaxArrivals], &pilot_[q]});
                energy += pilot_[q].energy, seen += pilot_[q].seen, kept += pilot_[q].count;
            }
        if (sources.empty()) return;
        for (Source& src : sources)
            src.weight = (energy > 0 ? double(src.pilot->energy) : double(src.pilot->seen)) /
                         src.pilot->count;
        const double total = energy > 0 ? energy : seen;
        const size_t m = std::min(kept, kMaxArrivals);
        // Merge the sorted sources in time order (a heap of each source's next quantile) and
        // emit the pool's m quantiles of equal weight.
        using Next = std::pair<float, size_t>;  // (time, source)
        std::priority_queue<Next, std::vector<Next>, std::greater<Next>> heap;
        std::vector<uint32_t> read(sources.size(), 0);
        for (size_t i = 0; i < sources.size(); ++i) heap.push({sources[i].times[0], i});
        double below = 0;
        size_t q = 0;
        while (!heap.empty() && q < m) {
            const auto [time, i] = heap.top();
            heap.pop();
            below += sources[i].weight;
            while (q < m && (double(q) + 0.5) / double(m) * total <= below) out[q++] = time;
            if (++read[i] < sources[i].pilot->count) heap.push({sources[i].times[read[i]], i});
        }
        for (; q < m; ++q) out[q] = out[q - 1];  // the last level, lost to rounding
        result.count = uint32_t(m);
        result.seen = uint32_t(std::min(seen, double(UINT32_MAX)));
        result.energy = float(energy);
        // k of the pool's arrivals, scaled to the m kept; at least 1 and at most m - 1.
        result.k = uint32_t(std::clamp<size_t>(
            size_t(std::lround(double(k_neighbors_) * double(m) / std::max(seen, 1.0))), 1, m - 1));
    }

    double clamp_bandwidth(double t) const {
        const double lo = 0.5 * grid_.bin_width,
                     hi = std::max(lo, 0.125 * grid_.bin_width * grid_.bins);
        return std::clamp(std::isnan(t) ? hi : t, lo, hi);
    }

    KernelShape shape_ = KernelShape::Perlin;
    double alpha_ = 0.8;
    double fixed_bandwidth_ = 0.0;
    size_t k_neighbors_ = 40;
    uint32_t pilot_spp_ = 64;
    int pilot_radius_ = 0;
    bool pilot_in_image_ = true;
    int width_ = 0, height_ = 0;
    TimeGrid grid_;
    std::vector<double> schedule_;   // T_j / T_1 for the first sample indices
    std::vector<PixelPilot> pilot_;  // per pixel
    std::vector<float> arrivals_;    // [pixel][kMaxArrivals]
    double max_t1_ = 0.0;
};

}  // namespace

FEMTO_PLUGIN(
    KernelFilter, femto::PluginKind::TemporalFilter, "kernel",
    "Progressive kernel density estimation in time (ch. 5.5): the bandwidth shrinks with "
    "every sample per pixel",
    {{"kernel", "string", "perlin", "kernel shape: box, epanechnikov, perlin or gaussian"},
     {"alpha", "float", "0.8",
      "shrinking rate: T_{j+1} / T_j = (j + alpha) / (j + 1); 4/5 minimises the asymptotic MSE"},
     {"bandwidth", "float", "",
      "initial half-width T_1 of the kernel (scene units); without it, a pilot pass estimates "
      "T_1 per pixel"},
     {"k_neighbors", "integer", "40",
      "pilot: T_1 at time t is the distance from t to its k-th nearest pilot arrival"},
     {"pilot_spp", "integer", "64", "pilot: samples per pixel of the pilot pass"},
     {"pilot_radius", "integer", "0",
      "pilot: each pixel pools the pilot arrivals of the pixels within this many pixels "
      "(1: 3x3), so that a shorter pilot gives it as many (0: its own only)"},
     {"pilot_in_image", "boolean", "true",
      "pilot: its samples are the image's first pilot_spp samples of each pixel (a tile keeps "
      "them in memory until its pixels' bandwidths are set), so the pilot costs no extra "
      "samples; false (the default when pilot_radius > 0): a separate pass with its own random "
      "streams. Integrators that splat or fix their samples per pass (light tracers, bdpt, "
      "ppm, beams) and pilots of over 2^16 samples per tile run it separately"}})
