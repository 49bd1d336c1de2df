// The transient film's block sums (plugins/films/transient/block_storage.h): the dense map and
// the open-addressing table must make the same entries, in the same order (the order of first
// touch, which the merge follows), with the same sums, and empty themselves for the next block.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include "films/transient/block_storage.h"

using femto::transient_film::BlockStorage;

namespace {

struct Touch {
    uint64_t key;
    double value;
};

// A block's worth of touches: runs of one pixel (a box filter's samples), then pixels revisited
// in any order (a wide filter, splats), over `pixels` pixels and `bins` bins.
std::vector<Touch> touches(size_t pixels, size_t bins, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<size_t> pixel(0, pixels - 1), bin(0, bins - 1), run(1, 6);
    std::uniform_real_distribution<double> value(0.0, 1.0);
    std::vector<Touch> out;
    for (size_t p = 0; p < pixels; ++p)
        for (size_t k = run(rng); k-- > 0;)
            out.push_back({uint64_t(bin(rng)) << 32 | p, value(rng)});
    for (int k = 0; k < 5000; ++k)
        out.push_back({uint64_t(bin(rng)) << 32 | pixel(rng), value(rng)});
    return out;
}

// Adds the touches as CubeBlock::add() does and returns the entries (key, red sum) in order.
std::vector<std::pair<uint64_t, double>> fill(BlockStorage& st, const std::vector<Touch>& t) {
    for (const Touch& x : t) st.entries[st.entry(x.key)].rgb[0] += x.value;
    std::vector<std::pair<uint64_t, double>> out;
    for (const auto& e : st.entries) out.push_back({e.key, e.rgb[0]});
    return out;
}

}  // namespace

TEST(TransientBlockStorage, MapAndTableMakeTheSameEntriesInTheSameOrder) {
    constexpr size_t kPixels = 400, kBins = 1024;  // a 16x16 tile with a Gaussian's border
    const std::vector<Touch> t = touches(kPixels, kBins, 7);
    BlockStorage dense(false, false, kBins);
    BlockStorage table(false, false, kBins, /*max_dense_slots=*/0);
    dense.prepare(kPixels);
    table.prepare(kPixels);
    ASSERT_TRUE(dense.dense_in_use);
    ASSERT_FALSE(table.dense_in_use);
    const auto a = fill(dense, t), b = fill(table, t);
    // The reference: first touches in order, sums by key.
    std::map<uint64_t, double> sums;
    std::vector<uint64_t> order;
    for (const Touch& x : t) {
        if (!sums.count(x.key)) order.push_back(x.key);
        sums[x.key] += x.value;
    }
    ASSERT_EQ(a.size(), order.size());
    ASSERT_EQ(b.size(), order.size());
    for (size_t e = 0; e < order.size(); ++e) {
        EXPECT_EQ(a[e].first, order[e]);
        EXPECT_EQ(b[e].first, order[e]);
        EXPECT_EQ(a[e].second, sums[order[e]]);  // the same additions in the same order
        EXPECT_EQ(b[e].second, sums[order[e]]);
    }
}

TEST(TransientBlockStorage, ClearedStorageServesTheNextBlockAsANewOne) {
    // The pool hands a storage from block to block, and a larger block may need the table
    // where a smaller one had the map (the map's limit is in slots: pixels x bins).
    constexpr size_t kBins = 64;
    BlockStorage reused(false, false, kBins, /*max_dense_slots=*/100 * kBins);
    for (const size_t pixels : {size_t(100), size_t(300), size_t(50), size_t(100)}) {
        SCOPED_TRACE(pixels);
        reused.prepare(pixels);
        EXPECT_EQ(reused.dense_in_use, pixels <= 100);
        BlockStorage fresh(false, false, kBins, 100 * kBins);
        fresh.prepare(pixels);
        const std::vector<Touch> t = touches(pixels, kBins, uint32_t(pixels));
        EXPECT_EQ(fill(reused, t), fill(fresh, t));
        reused.clear();
        EXPECT_TRUE(reused.entries.empty());
        EXPECT_TRUE(std::all_of(reused.dense.begin(), reused.dense.end(),
                                [](uint32_t e) { return e == 0; }));
        EXPECT_TRUE(std::all_of(reused.table.begin(), reused.table.end(),
                                [](uint32_t e) { return e == 0; }));
    }
}

TEST(TransientBlockStorage, MapsGrowOnlyWithinTheRoomTheyAreGiven) {
    // The film bounds all its storages' maps together: a storage whose map would need more
    // slots than the room left uses the table, and one whose map is large enough needs none.
    constexpr size_t kBins = 64;
    BlockStorage st(false, false, kBins);
    EXPECT_EQ(st.prepare(100, 100 * kBins - 1), 0u);  // one slot short: the table
    EXPECT_FALSE(st.dense_in_use);
    EXPECT_TRUE(st.dense.empty());
    EXPECT_EQ(st.prepare(100, 100 * kBins), 100 * kBins);  // room enough: the map
    EXPECT_TRUE(st.dense_in_use);
    EXPECT_EQ(st.prepare(50, 0), 0u);  // the map it has serves a smaller block
    EXPECT_TRUE(st.dense_in_use);
    EXPECT_EQ(st.prepare(150, 50 * kBins), 50 * kBins);  // grows by what the room allows
    EXPECT_TRUE(st.dense_in_use);
    EXPECT_EQ(st.prepare(200, 0), 0u);
    EXPECT_FALSE(st.dense_in_use);
    // Either way the entries are the same (MapAndTableMakeTheSameEntriesInTheSameOrder).
}
