// stratified: Mitsuba 3's `stratified` sampler. A pixel's N = n^2 samples (sample_count,
// rounded up to a perfect square as Mitsuba 3 does) share one stratification per dimension:
//
//  * Every call to next_1d() or next_2d() after start() opens the next dimension d (one
//    counter for both, as in Mitsuba 3). Dimension d of a pixel has its own random
//    permutation pi_d of the N strata, a pure function of (sampler seed, render seed, pixel,
//    d): sample i uses stratum pi_d(i).
//  * next_1d() splits [0, 1) into N strata [k/N, (k+1)/N); next_2d() splits [0, 1)^2 into
//    n x n cells, stratum k being the cell (k mod n, k div n).
//  * With `jitter` (default true) the value is uniform within its stratum (the offsets come
//    from a PCG32 seeded per pixel and sample, as `independent`'s numbers); without it, the
//    value is the stratum's centre.
//
// The permutation is Kensler's hash-based permutation ("Correlated Multi-Jittered Sampling",
// Pixar technical memo 13-01, 2013), the one Mitsuba 3 uses: it maps an index to its image
// without storing the permutation, so start() costs O(1) whatever N.
//
// Sample indices past N (progressive rendering, or `--spp` above sample_count) continue in
// blocks of N: block b = i div N uses permutations seeded with b too, so every complete block
// of N samples is stratified on its own. (Mitsuba 3 never draws such indices.)
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>

#include "femto/log.h"
#include "femto/plugin.h"
#include "femto/random.h"
#include "femto/sampler.h"

namespace {

/// Kensler's permutation of [0, length) keyed by `seed`: a hash that is a bijection of the
/// smallest power-of-two range holding `length` (every step is invertible on the masked low
/// bits, and high bits never flow down), cycle-walked until the image falls inside [0, length),
/// then rotated by the seed.
constexpr uint32_t kensler_permute(uint32_t index, uint32_t length, uint32_t seed) {
    uint32_t mask = length - 1;
    mask |= mask >> 1;
    mask |= mask >> 2;
    mask |= mask >> 4;
    mask |= mask >> 8;
    mask |= mask >> 16;
    uint32_t i = index;
    do {
        i ^= seed;
        i *= 0xe170893du;
        i ^= seed >> 16;
        i ^= (i & mask) >> 4;
        i ^= seed >> 8;
        i *= 0x0929eb3fu;
        i ^= seed >> 23;
        i ^= (i & mask) >> 1;
        i *= 1u | seed >> 27;
        i *= 0x6935fa69u;
        i ^= (i & mask) >> 11;
        i *= 0x74dcb303u;
        i ^= (i & mask) >> 2;
        i *= 0x9e501cc3u;
        i ^= (i & mask) >> 2;
        i *= 0xc860a3dfu;
        i &= mask;
        i ^= i >> 5;
    } while (i >= length);
    return uint32_t((uint64_t(i) + seed) % length);
}

/// (stratum + offset) / strata as a float inside [stratum / strata, (stratum + 1) / strata)
/// and below 1: rounding to float could otherwise carry a value near a stratum's upper edge
/// into the next stratum (or to 1).
float in_stratum(uint32_t stratum, float offset, uint32_t strata) {
    const double lo = double(stratum) / strata, hi = double(stratum + 1.0) / strata;
    float v = float((stratum + double(offset)) / strata);
    if (double(v) >= hi) v = std::nextafter(v, 0.f);
    if (double(v) < lo) v = std::nextafter(v, 1.f);
    return std::clamp(v, 0.f, 1.f - 0x1p-24f);
}

/// The side n of the n x n strata for a sample count: the smallest n with n^2 >= count.
uint32_t strata_side(uint32_t count) {
    auto side = uint32_t(std::sqrt(double(count)));
    while (uint64_t(side) * side < count) ++side;
    while (side > 1 && uint64_t(side - 1) * (side - 1) >= count) --side;
    return side;
}

class StratifiedSampler final : public femto::Sampler {
public:
    explicit StratifiedSampler(const femto::Properties& props)
        : Sampler(props), jitter_(props.get_bool("jitter", true)) {
        round_to_square(props);
        // Mitsuba 0.6's `dimension`: how many dimensions it stratified before falling back to
        // independent numbers. femto stratifies them all, as Mitsuba 3 does.
        if (props.has("dimension")) {
            const int64_t dimension = props.get_int("dimension");
            if (dimension <= 0)
                props.fail("dimension",
                           "\"dimension\" must be positive, got " + std::to_string(dimension));
            femto::log_note(props.location_of("dimension"),
                            "femto ignores dimension=" + std::to_string(dimension) +
                                " (its stratified sampler stratifies every dimension, as "
                                "Mitsuba 3's)");
        }
    }

    std::unique_ptr<femto::Sampler> clone() const override {
        return std::make_unique<StratifiedSampler>(*this);
    }

    void start(uint64_t seed, uint64_t pixel_index, uint32_t sample_index) override {
        const uint32_t block = sample_index / strata_;
        index_in_block_ = sample_index % strata_;
        pixel_key_ = femto::hash_combine(
            femto::hash_combine(femto::hash_combine(seed_, seed), pixel_index), block);
        dimension_ = 0;
        // The jitter offsets, like `independent`'s numbers, come from a generator of their own
        // per (pixel, sample); state and stream from two different hashes.
        const uint64_t h = femto::hash_combine(pixel_key_ ^ 0x6a09e667f3bcc909ULL, sample_index);
        rng_.seed(h, femto::mix64(h ^ 0x5851f42d4c957f2dULL));
    }

    float next_1d() override {
        const uint32_t stratum = next_stratum();
        return in_stratum(stratum, next_offset(), strata_);
    }

    femto::Vec2 next_2d() override {
        const uint32_t stratum = next_stratum();
        const float jx = next_offset(), jy = next_offset();
        return {in_stratum(stratum % side_, jx, side_), in_stratum(stratum / side_, jy, side_)};
    }

    uint64_t dimension() const override { return dimension_; }
    void advance_to(uint64_t d) override { dimension_ = std::max(dimension_, d); }

private:
    /// Mitsuba 3 rounds a sample count that is not a perfect square up to the next one, with
    /// a warning; so does femto, naming the count it uses.
    void round_to_square(const femto::Properties& props) {
        side_ = strata_side(sample_count_);
        const uint64_t rounded = uint64_t(side_) * side_;
        if (rounded > std::numeric_limits<uint32_t>::max())
            props.fail("sample_count",
                       fmt::format("\"sample_count\" {} rounds up to the perfect square {}, "
                                   "more than 2^32 - 1 samples",
                                   sample_count_, rounded));
        if (rounded != sample_count_)
            femto::log_warning(props.location_of("sample_count"),
                               fmt::format("the stratified sampler needs a perfect square "
                                           "sample_count: rounding {} up to {} ({} x {} strata)",
                                           sample_count_, rounded, side_, side_));
        strata_ = uint32_t(rounded);
        sample_count_ = strata_;
    }

    /// The stratum of the current sample in the next dimension.
    uint32_t next_stratum() {
        const auto permutation_seed =
            static_cast<uint32_t>(femto::hash_combine(pixel_key_, dimension_++));
        return kensler_permute(index_in_block_, strata_, permutation_seed);
    }

    float next_offset() { return jitter_ ? rng_.next_float() : 0.5f; }

    bool jitter_ = true;
    // The strata are fixed when the sampler is built (a later set_sample_count() changes how
    // many samples the renderer takes, not the strata): strata_ = side_ * side_.
    uint32_t side_ = 2;
    uint32_t strata_ = 4;
    uint64_t pixel_key_ = 0;
    uint32_t index_in_block_ = 0;
    uint64_t dimension_ = 0;
    femto::Pcg32 rng_;
};

}  // namespace

FEMTO_PLUGIN(StratifiedSampler, femto::PluginKind::Sampler, "stratified",
             "Stratified samples (Mitsuba 3's `stratified`): per pixel and dimension, a random "
             "permutation of N = n^2 strata (1-D) or n x n cells (2-D)",
             {{"sample_count", "integer", "4",
               "samples per pixel (> 0); not a perfect square: rounded up to the next one, with a "
               "warning"},
              {"jitter", "boolean", "true",
               "uniform offsets within each stratum; false: the stratum's centre"},
              {"dimension", "integer", "",
               "Mitsuba 0.6's stratified dimension count: accepted with a note; femto stratifies "
               "every dimension"}})
