// femto public API: a hashed uniform grid over points for fixed-radius queries (the photons of
// a photon-mapping pass, docs/photon-mapping.md).
//
// Written here rather than taken from a k-d tree library (nanoflann): every pass rebuilds the
// structure for one known radius, which a grid of cells of that size does in O(n) with a
// counting sort, and a query visits the 8 cells a ball of that radius can touch without
// allocating or sorting its results. The order in which a query visits points depends only on
// the points' order at build(), so estimates are bit-identical whatever the thread count.
#pragma once

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "femto/math.h"

namespace femto {

class PointGrid {
public:
    /// Indexes `points` for queries of radius up to `radius` (> 0). The grid keeps indices into
    /// the caller's array, which must outlive the queries.
    void build(const std::vector<Vec3>& points, float radius) {
        if (points.size() > size_t(UINT32_MAX))
            throw std::length_error("PointGrid: more than 2^32 - 1 points");
        cell_ = 2.f * radius;
        inv_cell_ = 1.f / cell_;
        buckets_ = 1;
        while (buckets_ < 2 * points.size() && buckets_ < (size_t(1) << 30)) buckets_ <<= 1;
        // Counting sort without temporaries (a pass's photon map is most of its memory): count
        // per bucket, prefix sums, place each point at its bucket's next slot (which moves each
        // start to the next bucket's), then shift the starts back.
        start_.assign(buckets_ + 1, 0);
        for (const Vec3& p : points) ++start_[bucket(cell_of(p)) + 1];
        for (size_t b = 0; b < buckets_; ++b) start_[b + 1] += start_[b];
        index_.resize(points.size());
        for (size_t i = 0; i < points.size(); ++i)
            index_[start_[bucket(cell_of(points[i]))]++] = uint32_t(i);
        for (size_t b = buckets_; b > 0; --b) start_[b] = start_[b - 1];
        start_[0] = 0;
    }

    /// Calls each(i) for every point i within `radius` (at most the build radius) of `x`,
    /// and possibly for some farther ones (the caller checks the distance): those of the 8 cells
    /// that the ball around x can overlap.
    template <typename Each>
    void query(const Vec3& x, Each&& each) const {
        if (index_.empty()) return;
        // The ball of radius cell/2 around x lies within the 2x2x2 cells nearest x.
        int lo[3];
        for (int a = 0; a < 3; ++a) lo[a] = to_int(x[a] * inv_cell_ - 0.5f);
        uint32_t seen[8];
        int visited = 0;
        for (int dz = 0; dz < 2; ++dz)
            for (int dy = 0; dy < 2; ++dy)
                for (int dx = 0; dx < 2; ++dx) {
                    const uint32_t b = bucket({lo[0] + dx, lo[1] + dy, lo[2] + dz});
                    bool again = false;  // two cells may hash to one bucket: visit it once
                    for (int k = 0; k < visited; ++k) again |= seen[k] == b;
                    if (again) continue;
                    seen[visited++] = b;
                    for (uint32_t j = start_[b]; j < start_[b + 1]; ++j) each(index_[j]);
                }
    }

private:
    struct Cell {
        int x, y, z;
    };
    Cell cell_of(const Vec3& p) const {
        return {to_int(p.x * inv_cell_), to_int(p.y * inv_cell_), to_int(p.z * inv_cell_)};
    }
    // Cell coordinate, clamped far beyond any scene (a NaN goes to cell 0).
    static int to_int(float v) {
        return v == v ? int(std::floor(std::fmin(std::fmax(v, -1e9f), 1e9f))) : 0;
    }
    uint32_t bucket(const Cell& c) const {
        // Teschner et al.'s spatial hash.
        const uint32_t h =
            (uint32_t(c.x) * 73856093u) ^ (uint32_t(c.y) * 19349663u) ^ (uint32_t(c.z) * 83492791u);
        return h & uint32_t(buckets_ - 1);
    }

    float cell_ = 1.f, inv_cell_ = 1.f;
    size_t buckets_ = 1;
    std::vector<uint32_t> start_;  // [buckets_ + 1]: bucket b holds index_[start_[b], start_[b+1])
    std::vector<uint32_t> index_;  // point indices, by bucket
};

}  // namespace femto
