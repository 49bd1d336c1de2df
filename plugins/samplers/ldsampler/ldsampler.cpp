// ldsampler: low-discrepancy samples from a "padded" Owen-scrambled (0,2)-sequence.
//
// The method (Kollig & Keller 2002 padding, with Burley 2020 "Practical Hash-based Owen
// Scrambling" for shuffling and scrambling):
//
//  * Every call to next_2d() or next_1d() after start() opens a new dimension slot d
//    (0, 1, 2, ...). Each slot gets its own seed s_d = hash(sampler seed, render seed, pixel, d).
//  * The sample index is shuffled per slot: i' = owen(i, s_d), a nested uniform scramble of the
//    index's bits. It is a bijection of the 32-bit indices that maps every aligned block of
//    2^k indices onto another aligned block of 2^k indices, so the first 2^k samples of a pixel
//    use one aligned block of the sequence, and different slots use unrelated orders: this
//    decorrelates the dimension pairs ("padding") without storing any permutation.
//  * next_2d() returns the first two Sobol dimensions at i': van der Corput (identity generator
//    matrix) and the second Sobol generator (the Pascal matrix mod 2). Together they are a
//    (0,2)-sequence in base 2, so every aligned block of 2^k points is a (0,k,2)-net: each
//    elementary interval of area 2^-k (2^a x 2^b strata, a + b = k) holds exactly one point.
//  * next_1d() returns the van der Corput dimension alone (a (0,1)-sequence: every aligned
//    block of 2^k points has one point in each interval [j/2^k, (j+1)/2^k)).
//  * Each output dimension is Owen-scrambled with the hash-based nested uniform scramble
//    (Laine-Karras style, with Vegdahl's improved hash), seeded by (s_d, component). Owen
//    scrambling keeps the net properties and makes the estimator unbiased; for smooth
//    integrands its variance falls as O(N^-3 log N) instead of O(N^-1).
//
// Everything is a pure function of (seed, pixel, sample, slot), so the numbers of a camera
// sample do not depend on the thread schedule, and any sample index works (progressive
// rendering past sample_count continues the same sequence). With sample_count a power of two
// each pixel's samples form a complete (0,k,2)-net in every dimension pair; other counts give
// a subset of one (at most one point per elementary interval).
#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>

#include "femto/plugin.h"
#include "femto/random.h"
#include "femto/sampler.h"

namespace {

/// The bits of x in reverse order: the bytes swapped, then the bits within each byte.
constexpr uint32_t reverse_bits(uint32_t x) {
    x = __builtin_bswap32(x);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    return ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
}
static_assert(reverse_bits(1u) == 0x80000000u && reverse_bits(0x12345678u) == 0x1e6a2c48u);

/// A random permutation of 32-bit words in which output bit i depends only on input bits
/// 0..i and the seed (every step only propagates information towards higher bits).
constexpr uint32_t laine_karras_permutation(uint32_t x, uint32_t seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

// Owen scrambling of a 32-bit binary fraction x (most significant bit = first digit), where
// the flip of each digit depends on all the digits before it, is then Burley's nested uniform
// scramble: owen(x, seed) = reverse_bits(laine_karras_permutation(reverse_bits(x), seed)).

/// The second Sobol dimension is y = C i over GF(2), with the generator matrix's columns
/// v_0 = 1 << 31, v_j = v_{j-1} ^ (v_{j-1} >> 1) (Pascal's triangle mod 2). Being linear, it is
/// tabulated per byte. The tables hold the bit-reversed y, which is what the scrambling below
/// consumes, and are indexed by the bytes of the bit-reversed index, which is what the index
/// shuffle produces: neither needs a reversal of its own.
struct SobolDim1Tables {
    uint32_t by_reversed_index[4][256];
    constexpr SobolDim1Tables() : by_reversed_index{} {
        uint32_t v[32] = {};
        v[0] = 1u << 31;
        for (int j = 1; j < 32; ++j) v[j] = v[j - 1] ^ (v[j - 1] >> 1);
        // Bit k of the reversed index r is bit 31 - k of the index.
        for (int b = 0; b < 4; ++b)
            for (uint32_t byte = 0; byte < 256; ++byte) {
                uint32_t y = 0;
                for (int k = 0; k < 8; ++k)
                    if (byte & (1u << k)) y ^= v[31 - (8 * b + k)];
                by_reversed_index[b][byte] = reverse_bits(y);
            }
    }
};
constexpr SobolDim1Tables kSobolDim1{};

/// reverse_bits(y) of the second Sobol dimension at index reverse_bits(r).
constexpr uint32_t sobol_dim1_reversed(uint32_t r) {
    const auto& t = kSobolDim1.by_reversed_index;
    return t[0][r & 0xffu] ^ t[1][(r >> 8) & 0xffu] ^ t[2][(r >> 16) & 0xffu] ^ t[3][r >> 24];
}

/// Reference definition of the same dimension, used to check the tables at compile time.
constexpr uint32_t sobol_dim1(uint32_t index) {
    uint32_t result = 0;
    for (uint32_t v = 1u << 31; index != 0; index >>= 1, v ^= v >> 1)
        if (index & 1u) result ^= v;
    return result;
}
static_assert(sobol_dim1(1) == 0x80000000u && sobol_dim1(2) == 0xc0000000u &&
              sobol_dim1(3) == 0x40000000u && sobol_dim1(4) == 0xa0000000u);
static_assert(sobol_dim1_reversed(reverse_bits(0xdeadbeefu)) ==
              reverse_bits(sobol_dim1(0xdeadbeefu)));
static_assert(sobol_dim1_reversed(reverse_bits(0x01234567u)) ==
              reverse_bits(sobol_dim1(0x01234567u)));

/// [0, 1) float from the 24 most significant bits (never rounds up to 1).
constexpr float to_unit_float(uint32_t x) { return static_cast<float>(x >> 8) * 0x1p-24f; }

constexpr uint32_t low32(uint64_t x) { return static_cast<uint32_t>(x); }

class LowDiscrepancySampler final : public femto::Sampler {
public:
    explicit LowDiscrepancySampler(const femto::Properties& props) : Sampler(props) {}

    std::unique_ptr<femto::Sampler> clone() const override {
        return std::make_unique<LowDiscrepancySampler>(*this);
    }

    void start(uint64_t seed, uint64_t pixel_index, uint32_t sample_index) override {
        pixel_seed_ = femto::hash_combine(femto::hash_combine(seed_, seed), pixel_index);
        // hash_combine(pixel_seed_, slot) = mix64(pixel_seed_ ^ (slot + slot_offset_)).
        slot_offset_ = 0x9e3779b97f4a7c15ULL + (pixel_seed_ << 6) + (pixel_seed_ >> 2);
        reversed_index_ = reverse_bits(sample_index);
        slot_ = 0;
    }

    // In both functions below, with s0, s1, s2 the slot's seeds and LK the permutation above:
    //   shuffled index  i = owen(index, s0)     = reverse(r), r = LK(reverse(index), s0)
    //   first dim.      x = owen(vdc(i), s1)    = reverse(LK(i, s1))   since vdc(i) = reverse(i)
    //   second dim.     y = owen(sobol1(i), s2) = reverse(LK(reverse(sobol1(i)), s2))
    // (reverse(sobol1(i)) is read from r directly: sobol_dim1_reversed).
    float next_1d() override {
        const Slot s = next_slot();
        const uint32_t r = laine_karras_permutation(reversed_index_, s.index_seed);
        return to_unit_float(reverse_bits(laine_karras_permutation(reverse_bits(r), s.x_seed)));
    }

    femto::Vec2 next_2d() override {
        const Slot s = next_slot();
        const uint32_t r = laine_karras_permutation(reversed_index_, s.index_seed);
        const uint32_t x = reverse_bits(laine_karras_permutation(reverse_bits(r), s.x_seed));
        const uint32_t y = reverse_bits(laine_karras_permutation(sobol_dim1_reversed(r), s.y_seed));
        return {to_unit_float(x), to_unit_float(y)};
    }

    uint64_t dimension() const override { return slot_; }
    void advance_to(uint64_t d) override { slot_ = std::max(slot_, d); }

private:
    struct Slot {
        uint32_t index_seed, x_seed, y_seed;
    };
    /// Seeds of the next dimension slot: hashes of (sampler seed, render seed, pixel, slot).
    Slot next_slot() {
        const uint64_t h = femto::mix64(pixel_seed_ ^ (slot_++ + slot_offset_));
        const uint64_t g = femto::mix64(h ^ 0x2545f4914f6cdd1dULL);
        return {low32(h), static_cast<uint32_t>(h >> 32), low32(g)};
    }

    uint64_t pixel_seed_ = 0;
    uint64_t slot_offset_ = 0;
    uint32_t reversed_index_ = 0;
    uint64_t slot_ = 0;
};

}  // namespace

FEMTO_PLUGIN(LowDiscrepancySampler, femto::PluginKind::Sampler, "ldsampler",
             "Padded, shuffled and Owen-scrambled (0,2)-sequence (Sobol dimensions 0 and 1 per "
             "pair); Mitsuba's `sobol` maps here",
             {{"sample_count", "integer", "4",
               "samples per pixel (> 0; a power of two gives complete (0,2)-nets)"}})
