// femto public API: a plugin's running totals, as a distributed render combines them.
//
// Under MPI (`mpirun -np N femto render`, docs/distributed.md) every process renders other
// samples of the same scene into its own copy of the film. At the end, rank 0 combines each
// process's totals into its own, element by element, in rank order, and writes. A film
// (Film::accumulators()) and an integrator that keeps images of its own
// (Integrator::accumulators()) list the arrays that hold their totals; everything else they
// keep must be the same in every process (parameters, a pilot's results).
#pragma once

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "femto/random.h"

namespace femto {

/// One array of running totals over the samples a process has seen.
struct Accumulator {
    enum class Type : uint8_t { Float64, Float32, UInt64 };
    /// How two processes' values combine: added (sums, counts) or the extreme kept (the
    /// earliest and latest arrival).
    enum class Op : uint8_t { Sum, Min, Max };

    Type type = Type::Float64;
    Op op = Op::Sum;
    void* data = nullptr;
    size_t count = 0;  ///< elements of `type`

    size_t element_bytes() const { return type == Type::Float32 ? 4 : 8; }

    static Accumulator of(std::vector<double>& v, Op op = Op::Sum) {
        return {Type::Float64, op, v.data(), v.size()};
    }
    static Accumulator of(std::vector<float>& v, Op op = Op::Sum) {
        return {Type::Float32, op, v.data(), v.size()};
    }
    /// An array of structs whose members are all doubles (e.g. PixelSums).
    template <typename DoublesOnly>
    static Accumulator of_doubles(std::vector<DoublesOnly>& v, Op op = Op::Sum) {
        static_assert(sizeof(DoublesOnly) % sizeof(double) == 0 && alignof(DoublesOnly) == 8,
                      "of_doubles() needs a struct of doubles");
        return {Type::Float64, op, v.data(), v.size() * (sizeof(DoublesOnly) / sizeof(double))};
    }
    static Accumulator of_doubles(double* p, size_t n, Op op = Op::Sum) {
        return {Type::Float64, op, p, n};
    }
    static Accumulator of_counts(uint64_t* p, size_t n) { return {Type::UInt64, Op::Sum, p, n}; }
};

/// Adds `value` to the float running total `total` without the drift of rounding to nearest.
/// Once a total is large against what is added to it, rounding to nearest loses the same part
/// of a steady addend every time, so the error grows in proportion to the additions: a film
/// voxel that received the same value in each of 65,536 passes of a progressive render was
/// off by up to 6.5e-4 (docs/design-notes.md). Here the exact sum double(total) + value is
/// rounded to one of the two floats around it at random, with the probabilities that make the
/// result exact on average (stochastic rounding): what remains is zero-mean noise that grows
/// as the square root of the additions, about 2^-24 sqrt(n / 3) of the total after n. `key`
/// draws the rounding (through a hash), so the same key gives the same bits: films use the
/// element's index and the pass, which keeps renders deterministic.
inline void add_without_drift(float& total, double value, uint64_t key) {
    const double exact = double(total) + value;
    const float nearest = float(exact);
    const double residual = exact - double(nearest);
    if (residual == 0.0 || !std::isfinite(exact)) {
        total = nearest;
        return;
    }
    // The float on the residual's side of `nearest` (one unit in the last place away).
    const bool up = residual > 0.0;
    float other;
    if (nearest == 0.f) {
        other = up ? std::numeric_limits<float>::denorm_min()
                   : -std::numeric_limits<float>::denorm_min();
    } else {
        const uint32_t bits = std::bit_cast<uint32_t>(nearest);
        other = std::bit_cast<float>((nearest > 0.f) == up ? bits + 1 : bits - 1);
    }
    const double gap = double(other) - double(nearest);  // 0 for a denormal under DAZ
    const double p = gap != 0.0 ? residual / gap : 0.0;  // in [0, 1/2]
    const double u = double(mix64(key) >> 11) * 0x1p-53;
    total = u < p ? other : nearest;
}

/// How a film adds each pass's totals into its float arrays: rounded to nearest for its first
/// kNearestPasses passes (at most 64 roundings, about 4e-6 of a total, and renders of that many
/// passes keep their bits), by add_without_drift() after, keyed by the pass and the element.
/// Only progressive integrators (one camera sample a pass) make more passes. A film keeps one,
/// calls start() from Film::start_pass() and add() in merge().
class PassTotals {
public:
    static constexpr uint32_t kNearestPasses = 64;

    void start(uint32_t pass) {
        pass_ = pass;
        ++started_;
    }
    /// True in the passes whose add() is `total += float(value)` (the first kNearestPasses):
    /// a film's hot loop may then add so itself.
    bool rounds_to_nearest() const { return started_ <= kNearestPasses; }
    /// Adds `value` to `total`, element `element` of its array; `salt` tells apart arrays
    /// whose elements share indices.
    void add(float& total, double value, uint64_t element, uint64_t salt = 0) const {
        if (rounds_to_nearest())
            total += float(value);
        else
            add_without_drift(total, value, hash_combine(pass_, element) ^ salt);
    }

private:
    uint32_t pass_ = 0, started_ = 0;
};

}  // namespace femto
