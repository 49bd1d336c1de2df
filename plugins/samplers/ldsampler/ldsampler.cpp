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
//
// Being pure functions of the slot, the slots of a sample are computed eight at a time in SIMD
// lanes when the integrator draws them in sequence (the path tracer): one slot's value is a
// chain of multiplications each waiting on the last, which lanes overlap. The numbers are the
// same either way (tests/unit/test_samplers.cpp checks them against the one-slot definition).
#include <algorithm>
#include <cstdint>
#include <memory>
#include <type_traits>

#include "femto/plugin.h"
#include "femto/random.h"
#include "femto/sampler.h"

namespace {

// Every helper below works on one 32- or 64-bit word and, unchanged, on eight of them in SIMD
// lanes (GCC's vector extensions: the same operators, scalars broadcast). A sampler drawing its
// dimensions in sequence gets eight slots computed at once (slot_values_batch()). The helpers
// change their operand in place: a vector passed or returned by value would cross from one
// instruction set's clone of slot_values_batch() into a function compiled for another, whose
// calling conventions differ (clang refuses it even where the call is inlined). The
// static_asserts check them on single words, through reverse_bits().
using U32x8 = uint32_t __attribute__((vector_size(32)));
using U64x8 = uint64_t __attribute__((vector_size(64)));

/// Reverses the order of the bits of each word of x: halves and bytes swapped (one bswap for a
/// single word), then nibbles, pairs and bits.
template <class U>
[[gnu::always_inline]] constexpr void reverse_bits_of(U& x) {
    if constexpr (std::is_same_v<U, uint32_t>) {
        x = __builtin_bswap32(x);
    } else {
        x = (x >> 16) | (x << 16);
        x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    }
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
}
constexpr uint32_t reverse_bits(uint32_t x) {
    reverse_bits_of(x);
    return x;
}
static_assert(reverse_bits(1u) == 0x80000000u && reverse_bits(0x12345678u) == 0x1e6a2c48u);

/// Applies to x a random permutation of 32-bit words in which output bit i depends only on
/// input bits 0..i and the seed (every step only propagates information towards higher bits).
template <class U>
[[gnu::always_inline]] constexpr void laine_karras_permute(U& x, const U& seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
}

// Owen scrambling of a 32-bit binary fraction x (most significant bit = first digit), where
// the flip of each digit depends on all the digits before it, is then Burley's nested uniform
// scramble: owen(x, seed) = reverse(laine_karras(reverse(x), seed)).

/// The second Sobol dimension, y = C i over GF(2) with the generator matrix's columns
/// v_0 = 1 << 31, v_j = v_{j-1} ^ (v_{j-1} >> 1) (Pascal's triangle mod 2): the reference
/// definition, for the checks below.
constexpr uint32_t sobol_dim1(uint32_t index) {
    uint32_t result = 0;
    for (uint32_t v = 1u << 31; index != 0; index >>= 1, v ^= v >> 1)
        if (index & 1u) result ^= v;
    return result;
}
static_assert(sobol_dim1(1) == 0x80000000u && sobol_dim1(2) == 0xc0000000u &&
              sobol_dim1(3) == 0x40000000u && sobol_dim1(4) == 0xa0000000u);

/// Replaces i by reverse_bits(sobol_dim1(i)), the form the scrambling consumes, without tables:
/// by Lucas' theorem C's entry (k, j) is binom(j, k) mod 2, which is 1 iff the bits of k are a
/// subset of j's, so digit k of y is the XOR of the index bits j at superset positions of k: a
/// superset transform in five shift-and-XOR steps (shifts vectorise where lookups do not).
template <class U>
[[gnu::always_inline]] constexpr void sobol_dim1_reversed_of(U& i) {
    i ^= (i >> 1) & 0x55555555u;
    i ^= (i >> 2) & 0x33333333u;
    i ^= (i >> 4) & 0x0f0f0f0fu;
    i ^= (i >> 8) & 0x00ff00ffu;
    i ^= i >> 16;
}
constexpr uint32_t sobol_dim1_reversed(uint32_t i) {
    sobol_dim1_reversed_of(i);
    return i;
}
static_assert(sobol_dim1_reversed(0xdeadbeefu) == reverse_bits(sobol_dim1(0xdeadbeefu)));
static_assert(sobol_dim1_reversed(0x01234567u) == reverse_bits(sobol_dim1(0x01234567u)));
static_assert(sobol_dim1_reversed(0xffffffffu) == reverse_bits(sobol_dim1(0xffffffffu)));

/// A single word reads the same from byte tables, indexed by the bits of r = reverse_bits(i)
/// that the index shuffle produces: that takes the reversal of i off the path to y.
struct SobolDim1Tables {
    uint32_t by_reversed_index[4][256];
    constexpr SobolDim1Tables() : by_reversed_index{} {
        for (int b = 0; b < 4; ++b)
            for (uint32_t byte = 0; byte < 256; ++byte)
                by_reversed_index[b][byte] = sobol_dim1_reversed(reverse_bits(byte << (8 * b)));
    }
};
constexpr SobolDim1Tables kSobolDim1{};
/// sobol_dim1_reversed(reverse_bits(r)), by the tables (the map is linear over GF(2)).
constexpr uint32_t sobol_dim1_reversed_from_r(uint32_t r) {
    const auto& t = kSobolDim1.by_reversed_index;
    return t[0][r & 0xffu] ^ t[1][(r >> 8) & 0xffu] ^ t[2][(r >> 16) & 0xffu] ^ t[3][r >> 24];
}
static_assert(sobol_dim1_reversed_from_r(0x89abcdefu) ==
              reverse_bits(sobol_dim1(reverse_bits(0x89abcdefu))));

/// Applies femto::mix64 (femto/random.h) to each word of z.
template <class U>
[[gnu::always_inline]] constexpr void mix64_of(U& z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
}
static_assert([] {
    uint64_t a = 12345, b = ~0ull;
    mix64_of(a);
    mix64_of(b);
    return a == femto::mix64(12345) && b == femto::mix64(~0ull);
}());

/// The low 32 bits of each 64-bit word of x, into low.
template <class U32, class U64>
[[gnu::always_inline]] constexpr void low_words_of(const U64& x, U32& low) {
    if constexpr (std::is_same_v<U64, uint64_t>)
        low = static_cast<uint32_t>(x);
    else
        low = __builtin_convertvector(x, U32);
}

/// The pair of dimension slot `slot` (a word, or a vector of slots) of the sample whose index
/// has the bits `reversed_index`; next_1d() returns x. With s0, s1, s2 the slot's seeds, hashes
/// of (sampler seed, render seed, pixel, slot), and LK the permutation above:
///   shuffled index  i = owen(index, s0)     = reverse(r), r = LK(reverse(index), s0)
///   first dim.      x = owen(vdc(i), s1)    = reverse(LK(i, s1))   since vdc(i) = reverse(i)
///   second dim.     y = owen(sobol1(i), s2) = reverse(LK(reverse(sobol1(i)), s2))
template <class U32, class U64>
[[gnu::always_inline]] constexpr void slot_values(const U64& slot, uint64_t pixel_seed,
                                                  uint64_t slot_offset, uint32_t reversed_index,
                                                  U32& x, U32& y) {
    // h = hash_combine(pixel_seed, slot) = mix64(pixel_seed ^ (slot + slot_offset)).
    U64 h = pixel_seed ^ (slot + slot_offset);
    mix64_of(h);
    U64 g = h ^ 0x2545f4914f6cdd1dULL;
    mix64_of(g);
    U32 s0{}, s1{}, s2{};
    low_words_of(h, s0);
    low_words_of(U64(h >> 32), s1);
    low_words_of(g, s2);
    U32 r = U32{} + reversed_index;
    laine_karras_permute(r, s0);
    U32 i = r;  // the shuffled index
    reverse_bits_of(i);
    if constexpr (std::is_same_v<U32, uint32_t>) {
        y = sobol_dim1_reversed_from_r(r);
    } else {
        y = i;
        sobol_dim1_reversed_of(y);
    }
    x = i;
    laine_karras_permute(x, s1);
    reverse_bits_of(x);
    laine_karras_permute(y, s2);
    reverse_bits_of(y);
}

constexpr uint64_t kSlotBatch = 8;

// GCC names the clones by x86-64 level (v4 includes AVX-512's 64-bit multiplications, which
// its "avx512f" alone lacks, and GCC takes no "avx512dq" clone); clang 14 by feature, since its
// dispatcher reads an arch= name as a CPU model, matches none, and would always run the baseline.
#if defined(__x86_64__) && defined(__clang__)
#define FEMTO_SLOT_BATCH_CLONES __attribute__((target_clones("avx512dq", "avx2", "default")))
#elif defined(__x86_64__)
#define FEMTO_SLOT_BATCH_CLONES \
    __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else  // other architectures: one version, for the target the plugin is built for
#define FEMTO_SLOT_BATCH_CLONES
#endif

/// slot_values() of slots first .. first + 7, into xs and ys. One slot's values are a chain of
/// hashes and permutations, each step waiting on the last, and the path waits on the draw; the
/// slots of a sample are independent of each other, so a sampler drawing in sequence computes
/// eight at a time in SIMD lanes. Compiled for AVX-512 (with its 64-bit multiplications), AVX2
/// and the x86-64 baseline (the loader picks what the CPU runs; the numbers are the same
/// integers on each).
FEMTO_SLOT_BATCH_CLONES void slot_values_batch(uint64_t first, uint64_t pixel_seed,
                                               uint64_t slot_offset, uint32_t reversed_index,
                                               uint32_t* xs, uint32_t* ys) {
    const U64x8 slots = U64x8{0, 1, 2, 3, 4, 5, 6, 7} + first;
    U32x8 x, y;
    slot_values(slots, pixel_seed, slot_offset, reversed_index, x, y);
    __builtin_memcpy(xs, &x, sizeof x);
    __builtin_memcpy(ys, &y, sizeof y);
}

/// [0, 1) float from the 24 most significant bits (never rounds up to 1).
constexpr float to_unit_float(uint32_t x) { return static_cast<float>(x >> 8) * 0x1p-24f; }

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
        batch_size_ = 0;
    }

    float next_1d() override {
        uint32_t x, y;
        draw(x, y);  // y, unused, is not computed for a slot alone (the inlined code drops it)
        return to_unit_float(x);
    }

    femto::Vec2 next_2d() override {
        uint32_t x, y;
        draw(x, y);
        return {to_unit_float(x), to_unit_float(y)};
    }

    uint64_t dimension() const override { return slot_; }
    void advance_to(uint64_t d) override { slot_ = std::max(slot_, d); }

private:
    /// The next slot's pair. Eight slots are computed at once at a sample's first slot and
    /// where the previous batch of eight ended: a sampler drawn in sequence, as the path tracer
    /// draws it. Elsewhere, after an advance_to() past the batch (BDPT's fixed layout: a vertex
    /// takes two or three numbers of a block of its own, too few to pay for a batch), each slot
    /// is computed alone, for the rest of the sample.
    [[gnu::always_inline]] void draw(uint32_t& x, uint32_t& y) {
        uint64_t k = slot_ - batch_first_;
        if (k >= batch_size_) {
            const bool in_sequence = slot_ == 0 || (batch_size_ == kSlotBatch && k == kSlotBatch);
            if (!in_sequence) {
                slot_values(slot_++, pixel_seed_, slot_offset_, reversed_index_, x, y);
                batch_size_ = 0;
                return;
            }
            slot_values_batch(slot_, pixel_seed_, slot_offset_, reversed_index_, xs_, ys_);
            batch_first_ = slot_;
            batch_size_ = kSlotBatch;
            k = 0;
        }
        ++slot_;
        x = xs_[k];
        y = ys_[k];
    }

    uint64_t pixel_seed_ = 0;
    uint64_t slot_offset_ = 0;
    uint32_t reversed_index_ = 0;
    uint64_t slot_ = 0;
    // The pairs of slots batch_first_ .. batch_first_ + batch_size_ - 1.
    uint64_t batch_first_ = 0;
    uint64_t batch_size_ = 0;
    uint32_t xs_[kSlotBatch] = {};
    uint32_t ys_[kSlotBatch] = {};
};

}  // namespace

FEMTO_PLUGIN(LowDiscrepancySampler, femto::PluginKind::Sampler, "ldsampler",
             "Padded, shuffled and Owen-scrambled (0,2)-sequence (Sobol dimensions 0 and 1 per "
             "pair); Mitsuba's `sobol` maps here",
             {{"sample_count", "integer", "4",
               "samples per pixel (> 0; a power of two gives complete (0,2)-nets)"}})
