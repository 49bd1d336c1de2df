#include "render/combine.h"

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace femto {

namespace {

double value_at(const Accumulator& a, const void* data, size_t i) {
    switch (a.type) {
        case Accumulator::Type::Float32:
            return double(static_cast<const float*>(data)[i]);
        case Accumulator::Type::Float64:
            return static_cast<const double*>(data)[i];
        case Accumulator::Type::UInt64:
            break;
    }
    return 0.0;
}

double combine(Accumulator::Op op, double a, double b) {
    switch (op) {
        case Accumulator::Op::Sum:
            return a + b;
        case Accumulator::Op::Min:
            return std::min(a, b);
        case Accumulator::Op::Max:
            return std::max(a, b);
    }
    return a;
}

// Counts stay integers (a double would round them beyond 2^53).
void combine_counts(const Accumulator& a, size_t offset, size_t n, int ranks,
                    std::vector<uint64_t>& buffer,
                    const std::function<void(int, void*, size_t)>& receive) {
    uint64_t* own = static_cast<uint64_t*>(a.data) + offset;
    buffer.resize(n);
    for (int r = 1; r < ranks; ++r) {
        receive(r, buffer.data(), n * sizeof(uint64_t));
        for (size_t i = 0; i < n; ++i) own[i] += buffer[i];
    }
}

}  // namespace

size_t chunk_elements(const Accumulator& a, size_t chunk_bytes) {
    return std::max<size_t>(1, chunk_bytes / a.element_bytes());
}

void send_accumulators(const std::vector<Accumulator>& own, size_t chunk_bytes,
                       const std::function<void(const void*, size_t)>& send) {
    for (const Accumulator& a : own) {
        const size_t step = chunk_elements(a, chunk_bytes), bytes = a.element_bytes();
        for (size_t offset = 0; offset < a.count; offset += step)
            send(static_cast<const char*>(a.data) + offset * bytes,
                 std::min(step, a.count - offset) * bytes);
    }
}

void combine_accumulators(const std::vector<Accumulator>& own, int ranks, size_t chunk_bytes,
                          const std::function<void(int, void*, size_t)>& receive) {
    std::vector<double> totals;
    std::vector<char> buffer;
    std::vector<uint64_t> counts;
    for (const Accumulator& a : own) {
        const size_t step = chunk_elements(a, chunk_bytes), bytes = a.element_bytes();
        for (size_t offset = 0; offset < a.count; offset += step) {
            const size_t n = std::min(step, a.count - offset);
            if (a.type == Accumulator::Type::UInt64) {
                combine_counts(a, offset, n, ranks, counts, receive);
                continue;
            }
            char* mine = static_cast<char*>(a.data) + offset * bytes;
            totals.resize(n);
            for (size_t i = 0; i < n; ++i) totals[i] = value_at(a, mine, i);
            buffer.resize(n * bytes);
            for (int r = 1; r < ranks; ++r) {
                receive(r, buffer.data(), n * bytes);
                for (size_t i = 0; i < n; ++i)
                    totals[i] = combine(a.op, totals[i], value_at(a, buffer.data(), i));
            }
            if (a.type == Accumulator::Type::Float64)
                std::memcpy(mine, totals.data(), n * sizeof(double));
            else
                for (size_t i = 0; i < n; ++i) reinterpret_cast<float*>(mine)[i] = float(totals[i]);
        }
    }
}

}  // namespace femto
