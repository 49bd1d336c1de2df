// femto public API: barycentric interpolation between sampled directions of the upper
// hemisphere, e.g. the light and view directions at which a BTF was measured (Bonn UBO2003: 81
// directions, UBO2014: 151, up to 75 degrees inclination).
//
// The directions are triangulated in the parabolic map p = (x, y) / (1 + z), which takes the
// upper hemisphere to the unit disk (as the Bonn btflib does): a Delaunay triangulation there
// has well-shaped triangles on the sphere too, and lines in the map are cheap to test. A query
// looks up a 32x32 grid of the triangles and hull edges near it, so it tests only a few
// triangles and never allocates: it runs about twice per BSDF evaluation.
#pragma once

#include <cstdint>
#include <vector>

#include "femto/math.h"

namespace femto {

class DirectionMesh {
public:
    /// Up to three sampled directions and their barycentric weights (>= 0, summing to 1;
    /// unused slots have weight 0 and index 0).
    struct Weights {
        uint32_t index[3] = {0, 0, 0};
        float weight[3] = {0, 0, 0};
    };

    /// Triangulates `directions` (unit, z >= 0). Throws std::invalid_argument with a clear
    /// message naming the offending direction index for: fewer than 3 directions, a non-finite
    /// or non-unit vector (|len-1| > 1e-3), z < -1e-6, two directions closer than 1e-5, or all
    /// directions collinear in the parabolic map (all in one plane through the z axis).
    /// Construction is O(n^2): meant for a few hundred directions.
    explicit DirectionMesh(std::vector<Vec3> directions);

    /// Interpolation weights for the unit direction d. Exact at the samples (weight 1 on the
    /// sample). Inside the convex hull of the samples (in the parabolic map): barycentric in the
    /// containing triangle. Outside (e.g. grazing directions beyond the last measured ring, or
    /// d.z < 0, which is first clamped to the horizon): the nearest point on the hull's
    /// boundary, linear between the two ends of that boundary edge. Continuous in d everywhere
    /// except at d = (0, 0, -1), whose horizon point is undefined (it takes azimuth 0). A
    /// non-finite d is treated as the zenith, so that a NaN does not crash a render.
    Weights interpolate(const Vec3& d) const;

    size_t size() const { return directions_.size(); }
    const std::vector<Vec3>& directions() const { return directions_; }
    /// 3 indices per triangle, counter-clockwise in the parabolic map.
    const std::vector<uint32_t>& triangles() const { return triangles_; }
    /// The hull's boundary in the parabolic map as (from, to) index pairs, counter-clockwise:
    /// the edges that directions outside the hull are projected onto.
    const std::vector<uint32_t>& boundary_edges() const { return boundary_; }

private:
    // Barycentric coordinates (b, c) of p in triangle (a, b, c) are inverse * (p - a).
    struct TriangleFrame {
        double ax, ay, inverse[4];
    };
    struct Edge {
        double ax, ay, dx, dy, inv_length2;
    };
    // Items (triangles or boundary edges) listed per grid cell: cell i holds
    // items[start[i]] .. items[start[i + 1] - 1].
    struct CellLists {
        std::vector<uint32_t> start, items;
    };
    static constexpr int kGrid = 32;

    void build_lookup();
    void fill_cell(int i, int j);
    int cell_of(double x, double y) const;
    Weights triangle_weights(uint32_t t, const double bary[3]) const;
    Weights edge_weights(double x, double y, uint32_t cell) const;

    std::vector<Vec3> directions_;
    std::vector<double> px_, py_;  // parabolic coordinates, double precision
    std::vector<uint32_t> triangles_;
    std::vector<uint32_t> boundary_;
    std::vector<TriangleFrame> frames_;
    std::vector<Edge> edges_;  // one per boundary edge, same order as boundary_
    CellLists cell_triangles_, cell_edges_;
    double grid_min_ = -1, grid_scale_ = 1;  // cell = floor((p - grid_min_) * grid_scale_)
};

}  // namespace femto
