// femto public API: a plugin's running totals, as a distributed render combines them.
//
// Under MPI (`mpirun -np N femto render`, docs/distributed.md) every process renders other
// samples of the same scene into its own copy of the film. At the end, rank 0 combines each
// process's totals into its own, element by element, in rank order, and writes. A film
// (Film::accumulators()) and an integrator that keeps images of its own
// (Integrator::accumulators()) list the arrays that hold their totals; everything else they
// keep must be the same in every process (parameters, a pilot's results).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

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

}  // namespace femto
