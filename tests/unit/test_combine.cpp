// Combining the accumulators of a distributed render (render/combine.h) without MPI: the
// "processes" are copies, the transport a queue of chunks.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <vector>

#include "render/combine.h"

namespace femto {
namespace {

// Three processes' totals of one film: float sums, double sums, counts, an earliest and a
// latest time.
struct Totals {
    std::vector<float> f;
    std::vector<double> d;
    uint64_t count = 0;
    double earliest = 0, latest = 0;
    std::vector<Accumulator> list() {
        return {Accumulator::of(f), Accumulator::of(d), Accumulator::of_counts(&count, 1),
                Accumulator::of_doubles(&earliest, 1, Accumulator::Op::Min),
                Accumulator::of_doubles(&latest, 1, Accumulator::Op::Max)};
    }
};

Totals make(int rank, size_t n) {
    Totals t;
    for (size_t i = 0; i < n; ++i) {
        t.f.push_back(float(i % 7) + 0.1f * float(rank + 1));
        t.d.push_back(double(i) * (rank + 1));
    }
    t.count = 1000 + uint64_t(rank);
    t.earliest = 5.0 - rank, t.latest = 10.0 + rank;
    return t;
}

// Runs the combination of `ranks` processes' totals into rank 0's with chunks of
// `chunk_bytes`, delivering each sender's chunks in the order it sent them.
void combine(std::vector<Totals>& procs, size_t chunk_bytes) {
    std::vector<std::deque<std::vector<char>>> sent(procs.size());
    for (size_t r = 1; r < procs.size(); ++r)
        send_accumulators(procs[r].list(), chunk_bytes, [&](const void* data, size_t bytes) {
            const char* p = static_cast<const char*>(data);
            sent[r].emplace_back(p, p + bytes);
        });
    combine_accumulators(procs[0].list(), int(procs.size()), chunk_bytes,
                         [&](int r, void* buffer, size_t bytes) {
                             ASSERT_FALSE(sent[size_t(r)].empty());
                             ASSERT_EQ(sent[size_t(r)].front().size(), bytes);
                             std::memcpy(buffer, sent[size_t(r)].front().data(), bytes);
                             sent[size_t(r)].pop_front();
                         });
    for (size_t r = 1; r < procs.size(); ++r) EXPECT_TRUE(sent[r].empty()) << "rank " << r;
}

TEST(CombineAccumulators, AddsSumsAndKeepsExtremesAcrossChunks) {
    const size_t n = 1001;
    for (const size_t chunk_bytes : {size_t(24), size_t(4096), size_t(1) << 20}) {
        std::vector<Totals> procs;
        for (int r = 0; r < 3; ++r) procs.push_back(make(r, n));
        combine(procs, chunk_bytes);
        const Totals& root = procs[0];
        for (size_t i = 0; i < n; ++i) {
            // Float totals: the three values added in double, rounded once.
            const double expected =
                double(make(0, n).f[i]) + double(make(1, n).f[i]) + double(make(2, n).f[i]);
            ASSERT_EQ(root.f[i], float(expected)) << i << " chunk " << chunk_bytes;
            ASSERT_EQ(root.d[i], double(i) * 6) << i;
        }
        EXPECT_EQ(root.count, 3003u);
        EXPECT_EQ(root.earliest, 3.0);
        EXPECT_EQ(root.latest, 12.0);
    }
}

TEST(CombineAccumulators, FloatTotalsAreRoundedOnce) {
    // 1 + 2^-24 + 2^-24 in float, added pairwise, stays 1; in double, rounded once, it is
    // 1 + 2^-23.
    std::vector<Totals> procs(3);
    const float tiny = std::ldexp(1.f, -24);
    procs[0].f = {1.f}, procs[1].f = {tiny}, procs[2].f = {tiny};
    for (Totals& t : procs) t.d = {0.0};
    combine(procs, 4096);
    EXPECT_EQ(procs[0].f[0], 1.f + 2 * tiny);
}

TEST(CombineAccumulators, CountsStayExactBeyondDoublePrecision) {
    std::vector<Totals> procs(2);
    procs[0].count = (uint64_t(1) << 53) + 1, procs[1].count = 1;
    combine(procs, 4096);
    EXPECT_EQ(procs[0].count, (uint64_t(1) << 53) + 2);
}

}  // namespace
}  // namespace femto
