// Combining the accumulators of a distributed render (render/combine.h) without MPI: the
// "processes" are copies, the transport a queue of chunks.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <vector>

#include "femto/accumulator.h"
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

// add_without_drift(): adding 1 to a float total of 2^24 (a unit in the last place is 2 there)
// is a tie that rounding to nearest (to even) loses every time. Stochastically rounded, 10^4
// additions arrive on average: each rounds by -1 or +1 with equal chance, so the total ends
// within 5 standard deviations (5 sqrt(10^4) = 500) of 2^24 + 10^4. The same keys give the
// same bits; a value the float holds exactly is added exactly.
TEST(AddWithoutDrift, AddendsBelowHalfAUnitArriveOnAverage) {
    constexpr int kAdds = 10000;
    const float start = std::ldexp(1.f, 24);
    float nearest = start, total = start, again = start;
    for (int i = 0; i < kAdds; ++i) {
        nearest += 1.f;
        add_without_drift(total, 1.0, uint64_t(i));
        add_without_drift(again, 1.0, uint64_t(i));
    }
    EXPECT_EQ(nearest, start);
    EXPECT_NEAR(double(total), double(start) + kAdds, 500.0);
    EXPECT_EQ(total, again);
    float exact = 0.25f;
    add_without_drift(exact, 0.5, 7);
    EXPECT_EQ(exact, 0.75f);
    float zero = 0.f;
    add_without_drift(zero, 1e-50, 7);  // below the smallest float: 0 or the smallest denormal
    EXPECT_TRUE(zero == 0.f || zero == std::numeric_limits<float>::denorm_min());
}

}  // namespace
}  // namespace femto
