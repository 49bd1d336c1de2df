// The transient film's per-block sums (internal to the plugin; its own header so that the unit
// tests can check the map against the table directly).
#pragma once

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "femto/tfilter.h"

// Internal linkage (one translation unit uses it: the plugin's, or a test's), as when it lay in
// transient.cpp: the compiler then inlines the entries' append into every contribution's add.
namespace femto::transient_film {
namespace {

// A block's sums: one entry per (block pixel, bin) the block received. A pass gives a tile's
// block a few contributions per pixel spread over all of its bins (a 32x32 tile of 1024 bins
// would be 25 MB dense), so a dense block missed the cache on almost every contribution; the
// entries of a pass fit in the L2 cache instead, and the merge walks them in order.
// Finding a (pixel, bin)'s entry: a dense map of entry numbers, 4 bytes per (block pixel, bin)
// (the renderer's tile rule keeps a block under 1/32 of the film's pixels where it can). The
// samples of a tile come pixel by pixel, so the map's slices in use are those of the pixels the
// reconstruction filter reaches from the current one, a few rows of the block: they stay in
// the cache. (An open-addressing table found them before: with a Gaussian filter each
// sample's 16 pixels hashed and probed it, and the map renders such a film 13 % faster.)
// Grids too large for a map (kMaxDenseSlots), and blocks whose map would take the film's maps
// past 1/8 of the cube's bytes (many threads), use that table. Both make the entries in the order
// of their first touch: the merge is the same either way. Recycled through the film's pool, empty
// between uses.
struct BlockStorage {
    // Double: a pass may add many contributions to one entry (a light tracer's splats onto a
    // one-pixel meter: every light path of the pass), and float sums of that many lose digits.
    struct Entry {
        uint64_t key;  // bin << 32 | block pixel (the merge takes them apart without dividing)
        double rgb[3];
    };
    // 16 MiB of map: 1024 bins for any tile (32x32 plus a border of up to 16), 4096 bins for a
    // 16x16 tile with a border of up to 8.
    static constexpr size_t kMaxDenseSlots = size_t(1) << 22;
    std::vector<Entry> entries;  // in the order of their first touch
    std::vector<double> sq;      // [entry][3] sum of w * (per-sample bin value)^2 (variance)
    std::vector<float> count;    // [entry] contributions (aovs="count")
    std::vector<PixelSums> weights;
    const bool variance, counts;  // the storage keeps the second moment / the counts
    const size_t bins;
    const size_t max_dense;
    bool dense_in_use = true;     // for the current block: the map, or else the table
    std::vector<uint32_t> dense;  // [block pixel * bins + bin]: entry + 1, or 0
    std::vector<uint32_t> table;  // open addressing, linear probing: entry + 1, or 0 (free)
    int shift = 64;               // 64 - log2(table size)

    /// `max_dense_slots`: the largest map (block pixels x bins) it makes; beyond, the table.
    BlockStorage(bool with_variance, bool with_counts, size_t grid_bins,
                 size_t max_dense_slots = kMaxDenseSlots)
        : variance(with_variance),
          counts(with_counts),
          bins(grid_bins),
          max_dense(max_dense_slots) {}

    /// Readies the (empty) storage for a block of `pixels` pixels. `map_room`: how many map
    /// slots it may add (the film bounds all its storages' maps together); where its map would
    /// pass that or max_dense, the block uses the table. Returns the slots it added.
    size_t prepare(size_t pixels, size_t map_room = SIZE_MAX) {
        if (weights.size() < pixels) weights.resize(pixels);  // all zero between uses
        const size_t slots = pixels <= max_dense / bins ? pixels * bins : SIZE_MAX;
        const size_t added = slots > dense.size() ? slots - dense.size() : 0;
        dense_in_use = slots != SIZE_MAX && added <= map_room;
        if (!dense_in_use) {
            if (table.empty()) grow();
            return 0;
        }
        if (added > 0) dense.resize(slots, 0);
        return added;
    }

    /// The entry of `key`, created (zero) on its first touch.
    size_t entry(uint64_t key) {
        if (dense_in_use) {
            uint32_t& e = dense[slot(key)];
            if (e == 0) e = uint32_t(append(key) + 1);
            return e - 1;
        }
        return find(key);
    }
    /// Empties the entries and the map or table (keeping their memory for the next block).
    void clear() {
        if (dense_in_use) {
            for (const Entry& en : entries) dense[slot(en.key)] = 0;
        } else {
            // Latest first: the slots between an entry's home and its own hold earlier entries
            // (so it was when it was placed, and growing re-places them in order), still there.
            for (size_t e = entries.size(); e-- > 0;)
                for (size_t i = home(entries[e].key); table[i] != 0; i = next(i))
                    if (table[i] == e + 1) {
                        table[i] = 0;
                        break;
                    }
        }
        entries.clear();
        sq.clear();
        count.clear();
    }

private:
    size_t slot(uint64_t key) const { return size_t(key & 0xffffffffu) * bins + (key >> 32); }
    [[gnu::noinline]] size_t find(uint64_t key) {  // through the table
        for (size_t i = home(key);; i = next(i)) {
            const uint32_t e = table[i];
            if (e == 0) return insert(key, i);
            if (entries[e - 1].key == key) return e - 1;
        }
    }
    size_t home(uint64_t key) const {  // Fibonacci hashing: neighbouring keys spread apart
        return size_t((key * 0x9E3779B97F4A7C15ull) >> shift);
    }
    size_t next(size_t slot) const { return (slot + 1) & (table.size() - 1); }
    size_t free_slot(uint64_t key) const {  // where linear probing places a new key
        size_t slot = home(key);
        while (table[slot] != 0) slot = next(slot);
        return slot;
    }
    size_t insert(uint64_t key, size_t slot) {
        if (2 * (entries.size() + 1) > table.size()) {  // keep the load at most 1/2
            grow();
            slot = free_slot(key);
        }
        const size_t e = append(key);
        table[slot] = uint32_t(e + 1);
        return e;
    }
    size_t append(uint64_t key) {  // a new zero entry
        const size_t e = entries.size();
        // Small enough to inline into entry(), which every contribution calls: the AOVs'
        // arrays and the overflow check are out of line.
        if (e + 1 > std::numeric_limits<uint32_t>::max() || variance || counts)
            return append_with_aovs(key);
        entries.push_back({key, {0, 0, 0}});
        return e;
    }
    [[gnu::noinline]] size_t append_with_aovs(uint64_t key) {
        const size_t e = entries.size();
        if (e + 1 > std::numeric_limits<uint32_t>::max()) throw std::length_error("block entries");
        entries.push_back({key, {0, 0, 0}});
        try {  // an allocation that fails leaves the storage as it was
            if (variance) sq.insert(sq.end(), 3, 0.0);
            if (counts) count.push_back(0.f);
        } catch (...) {
            entries.pop_back();
            if (variance) sq.resize(3 * e);
            throw;
        }
        return e;
    }
    void grow() { rehash(std::max<size_t>(4096, 2 * table.size())); }
    // A table of `slots` (a power of two) holding every entry, placed in order.
    void rehash(size_t slots) {
        table.assign(slots, 0);
        shift = 64 - std::countr_zero(table.size());
        for (size_t e = 0; e < entries.size(); ++e)
            table[free_slot(entries[e].key)] = uint32_t(e + 1);
    }
};

}  // namespace
}  // namespace femto::transient_film
