// DirectionMesh (femto/direction_mesh.h): Delaunay triangulation of sampled directions in the
// parabolic map, and the grid that makes a lookup test only a few triangles.
//
// Written by hand: femto's dependencies (Embree, OIIO, OpenEXR, OCIO, pugixml, TBB, GTest,
// benchmark, CLI11, fmt, zlib, MPI) include no triangulation library, and a few hundred points
// need only a Bowyer-Watson insertion of ~100 lines (O(n^2), a few milliseconds for the Bonn
// BTFs' 151 directions).
//
// Robustness: the Bonn samplings lie on rings, so many points are exactly cocircular and the
// in-circle test is zero up to rounding. A triangle joins the cavity of a new point only when
// its circumcircle certainly contains the point (the determinant exceeds its rounding-error
// bound, after Shewchuk); then the cavity is grown until every edge of its boundary certainly
// sees the new point. A cavity whose boundary edges all see the point is one star-shaped region
// around it, so the new fan of triangles neither overlaps nor leaves holes, whatever the
// rounding; cocircular points get one of their equally valid triangulations. The super-triangle
// is 1e5 times larger than the points, so that it cuts off no hull edge unless a sample lies
// within ~1e-5 of the segment between two hull vertices; the constructor checks that the
// triangles cover the convex hull and says which directions are at fault otherwise.
#include "femto/direction_mesh.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace femto {
namespace {

struct Point {
    double x, y;
};
struct Triangle {
    uint32_t v[3];
};

constexpr double kEps = std::numeric_limits<double>::epsilon();

// Twice the signed area of (a, b, c), and whether it is certainly positive (Shewchuk's bound
// on its rounding error is 3.3 eps times the sum of the magnitudes of its products).
double orient(Point a, Point b, Point c) {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}
bool certainly_ccw(Point a, Point b, Point c) {
    const double l = (b.x - a.x) * (c.y - a.y), r = (b.y - a.y) * (c.x - a.x);
    return l - r > 4 * kEps * (std::abs(l) + std::abs(r));
}

// Whether p is certainly inside the circumcircle of the counter-clockwise (a, b, c).
bool certainly_in_circle(Point a, Point b, Point c, Point p) {
    const double ax = a.x - p.x, ay = a.y - p.y, bx = b.x - p.x, by = b.y - p.y;
    const double cx = c.x - p.x, cy = c.y - p.y;
    const double a2 = ax * ax + ay * ay, b2 = bx * bx + by * by, c2 = cx * cx + cy * cy;
    const double bc = bx * cy - by * cx, ca = cx * ay - cy * ax, ab = ax * by - ay * bx;
    const double bound = a2 * (std::abs(bx * cy) + std::abs(by * cx)) +
                         b2 * (std::abs(cx * ay) + std::abs(cy * ax)) +
                         c2 * (std::abs(ax * by) + std::abs(ay * bx));
    return a2 * bc + b2 * ca + c2 * ab > 12 * kEps * bound;
}

uint64_t edge_key(uint32_t from, uint32_t to) { return uint64_t(from) << 32 | to; }

std::string describe(size_t i, const Vec3& d) {
    std::ostringstream s;
    s << "direction " << i << " (" << d.x << ", " << d.y << ", " << d.z << ")";
    return s.str();
}

[[noreturn]] void fail(const std::string& message) {
    throw std::invalid_argument("DirectionMesh: " + message);
}

void validate_each(const std::vector<Vec3>& dirs) {
    if (dirs.size() < 3) fail("needs at least 3 directions, got " + std::to_string(dirs.size()));
    if (dirs.size() > (size_t(1) << 24)) fail("too many directions");
    for (size_t i = 0; i < dirs.size(); ++i) {
        const Vec3& d = dirs[i];
        if (!is_finite(d)) fail(describe(i, d) + " is not finite");
        const double len = std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z);
        if (std::abs(len - 1) > 1e-3)
            fail(describe(i, d) + " is not a unit vector (length " + std::to_string(len) + ")");
        if (d.z < -1e-6f) fail(describe(i, d) + " is below the horizon (z < -1e-6)");
    }
    for (size_t i = 0; i < dirs.size(); ++i)
        for (size_t j = i + 1; j < dirs.size(); ++j)
            if (distance_between(dirs[i], dirs[j]) < 1e-5)
                fail(describe(j, dirs[j]) + " is closer than 1e-5 to " + describe(i, dirs[i]));
}

// Throws unless some point lies off the line through the first point and the one farthest from
// it, by more than 1e-6 of their distance (float directions in one plane through the z axis
// scatter about that much).
void validate_not_collinear(const std::vector<Point>& pts) {
    size_t far = 0;
    double far2 = 0;
    for (size_t i = 1; i < pts.size(); ++i) {
        const double dx = pts[i].x - pts[0].x, dy = pts[i].y - pts[0].y;
        if (dx * dx + dy * dy > far2) far2 = dx * dx + dy * dy, far = i;
    }
    for (const Point& p : pts)
        if (std::abs(orient(pts[0], pts[far], p)) > 1e-6 * far2) return;
    fail("all " + std::to_string(pts.size()) +
         " directions are collinear in the parabolic map (they lie in one plane through the z "
         "axis, e.g. directions 0 and " +
         std::to_string(far) + ")");
}

// Incremental Delaunay triangulation (Bowyer-Watson) of `pts`, whose last three entries are the
// super-triangle's corners; returns the triangles of the first n = pts.size() - 3 points.
class BowyerWatson {
public:
    explicit BowyerWatson(const std::vector<Point>& pts) : pts_(pts) {
        const uint32_t n = uint32_t(pts.size() - 3);
        tris_.push_back({{n, n + 1, n + 2}});
        for (uint32_t i = 0; i < n; ++i) insert(i);
        std::erase_if(tris_, [n](const Triangle& t) {
            return std::max({t.v[0], t.v[1], t.v[2]}) >= n;
        });
    }
    std::vector<Triangle> triangles() const { return tris_; }

private:
    void insert(uint32_t i) {
        const Point p = pts_[i];
        std::unordered_map<uint64_t, uint32_t> owner;  // directed edge -> triangle
        in_cavity_.assign(tris_.size(), 0);
        for (uint32_t t = 0; t < tris_.size(); ++t) {
            const auto& v = tris_[t].v;
            for (int k = 0; k < 3; ++k) owner[edge_key(v[k], v[(k + 1) % 3])] = t;
            in_cavity_[t] = certainly_in_circle(pts_[v[0]], pts_[v[1]], pts_[v[2]], p) ||
                            may_contain(tris_[t], p);
        }
        while (grow_until_visible(p, owner)) {
        }
        std::vector<Triangle> kept;
        for (uint32_t t = 0; t < tris_.size(); ++t) {
            if (!in_cavity_[t]) {
                kept.push_back(tris_[t]);
                continue;
            }
            const auto& v = tris_[t].v;
            for (int k = 0; k < 3; ++k)
                if (!shares_cavity_edge(v[(k + 1) % 3], v[k], owner))
                    fan_.push_back({{v[k], v[(k + 1) % 3], i}});
        }
        kept.insert(kept.end(), fan_.begin(), fan_.end());
        fan_.clear();
        tris_ = std::move(kept);
    }

    // Whether p may lie in triangle t (on no edge's outer side for certain): the triangle(s)
    // holding p always belong to its cavity, even if rounding hides p from their circumcircle.
    bool may_contain(const Triangle& t, Point p) const {
        for (int k = 0; k < 3; ++k)
            if (certainly_ccw(pts_[t.v[(k + 1) % 3]], pts_[t.v[k]], p)) return false;
        return true;
    }

    bool shares_cavity_edge(uint32_t from, uint32_t to,
                            const std::unordered_map<uint64_t, uint32_t>& owner) const {
        const auto it = owner.find(edge_key(from, to));
        return it != owner.end() && in_cavity_[it->second];
    }

    // Adds to the cavity the triangle beyond each boundary edge that does not certainly see p;
    // returns whether it added any.
    bool grow_until_visible(Point p, const std::unordered_map<uint64_t, uint32_t>& owner) {
        bool grown = false;
        for (uint32_t t = 0; t < tris_.size(); ++t) {
            if (!in_cavity_[t]) continue;
            const auto& v = tris_[t].v;
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = v[k], b = v[(k + 1) % 3];
                if (shares_cavity_edge(b, a, owner) || certainly_ccw(pts_[a], pts_[b], p)) continue;
                const auto beyond = owner.find(edge_key(b, a));
                if (beyond == owner.end())  // p is deep inside the super-triangle
                    throw std::logic_error("DirectionMesh: point outside the super-triangle");
                in_cavity_[beyond->second] = 1;
                grown = true;
            }
        }
        return grown;
    }

    std::vector<Point> pts_;
    std::vector<Triangle> tris_, fan_;
    std::vector<char> in_cavity_;
};

std::vector<Point> super_triangle_around(const std::vector<Point>& pts) {
    double lo_x = pts[0].x, hi_x = lo_x, lo_y = pts[0].y, hi_y = lo_y;
    for (const Point& p : pts) {
        lo_x = std::min(lo_x, p.x), hi_x = std::max(hi_x, p.x);
        lo_y = std::min(lo_y, p.y), hi_y = std::max(hi_y, p.y);
    }
    const double cx = (lo_x + hi_x) / 2, cy = (lo_y + hi_y) / 2;
    const double r = 1e5 * std::max({hi_x - lo_x, hi_y - lo_y, 1e-3});
    // Counter-clockwise, equilateral, inradius r / 2.
    return {{cx, cy + r},
            {cx - r * 0.8660254037844386, cy - r / 2},
            {cx + r * 0.8660254037844386, cy - r / 2}};
}

// Area of the convex hull of `pts` (Andrew's monotone chain).
double hull_area(std::vector<Point> pts) {
    std::sort(pts.begin(), pts.end(),
              [](Point a, Point b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
    std::vector<Point> hull(2 * pts.size());
    size_t k = 0;
    for (int pass = 0; pass < 2; ++pass) {
        const size_t floor = k;
        for (size_t j = 0; j < pts.size(); ++j) {
            const Point p = pass == 0 ? pts[j] : pts[pts.size() - 1 - j];
            while (k >= floor + 2 && orient(hull[k - 2], hull[k - 1], p) <= 0) --k;
            hull[k++] = p;
        }
        --k;  // the last point of each chain starts the next
    }
    double area = 0;
    for (size_t j = 0; j < k; ++j) area += orient(hull[0], hull[j], hull[(j + 1) % k]);
    return area / 2;
}

// The boundary of the triangulated region as (from, to) pairs: the edges without a twin.
std::vector<uint32_t> boundary_of(const std::vector<uint32_t>& tris) {
    std::unordered_map<uint64_t, int> count;
    for (size_t t = 0; t < tris.size(); t += 3)
        for (int k = 0; k < 3; ++k) count[edge_key(tris[t + k], tris[t + (k + 1) % 3])]++;
    std::vector<uint32_t> boundary;
    for (size_t t = 0; t < tris.size(); t += 3)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = tris[t + k], b = tris[t + (k + 1) % 3];
            if (!count.contains(edge_key(b, a))) boundary.insert(boundary.end(), {a, b});
        }
    return boundary;
}

// Throws if the triangles miss part of the convex hull (a sample too close to a hull edge for
// the super-triangle to resolve), naming the directions along the gap.
void check_covers_hull(const std::vector<Point>& pts, const std::vector<uint32_t>& tris,
                       const std::vector<uint32_t>& boundary) {
    double area = 0;
    for (size_t t = 0; t < tris.size(); t += 3)
        area += orient(pts[tris[t]], pts[tris[t + 1]], pts[tris[t + 2]]) / 2;
    const double hull = hull_area(pts);
    if (std::abs(area - hull) <= 1e-9 * hull) return;
    for (size_t e = 0; e < boundary.size(); e += 2)
        for (size_t f = 0; f < boundary.size(); f += 2)
            if (boundary[f] == boundary[e + 1] &&
                orient(pts[boundary[e]], pts[boundary[e + 1]], pts[boundary[f + 1]]) < 0)
                fail("directions " + std::to_string(boundary[e]) + ", " +
                     std::to_string(boundary[e + 1]) + " and " + std::to_string(boundary[f + 1]) +
                     " are too nearly collinear on the hull of the parabolic map to triangulate");
    fail("the triangulation does not cover the convex hull of the directions");
}

double distance_to_segment(double x, double y, Point a, Point b) {
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double t = std::clamp(((x - a.x) * dx + (y - a.y) * dy) / (dx * dx + dy * dy), 0., 1.);
    return std::hypot(x - a.x - t * dx, y - a.y - t * dy);
}

// The parabolic map (x, y) / (|d| + z) of d: (x, y) / (1 + z) for unit d, and scale-free, so
// that a float direction maps to the same point whether its length rounds to 1 or not (the
// samples must map exactly where interpolate() looks them up). Below the horizon: the horizon
// point of the same azimuth (azimuth 0 for the nadir); non-finite d: the zenith.
Point parabolic(const Vec3& d) {
    const double x = d.x, y = d.y, z = d.z, rxy = std::sqrt(x * x + y * y);
    Point p{1, 0};
    if (z >= 0) {
        const double s = 1 / (std::sqrt(rxy * rxy + z * z) + z);
        p = {x * s, y * s};
    } else if (rxy > 0) {
        p = {x / rxy, y / rxy};
    }
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !is_finite(d)) p = {0, 0};
    return p;
}

}  // namespace

DirectionMesh::DirectionMesh(std::vector<Vec3> directions) : directions_(std::move(directions)) {
    validate_each(directions_);
    std::vector<Point> pts;
    for (const Vec3& d : directions_) {
        pts.push_back(parabolic(d));
        px_.push_back(pts.back().x);
        py_.push_back(pts.back().y);
    }
    validate_not_collinear(pts);
    std::vector<Point> with_super = pts;
    for (const Point& corner : super_triangle_around(pts)) with_super.push_back(corner);
    for (const Triangle& t : BowyerWatson(with_super).triangles())
        triangles_.insert(triangles_.end(), t.v, t.v + 3);
    boundary_ = boundary_of(triangles_);
    check_covers_hull(pts, triangles_, boundary_);
    build_lookup();
}

int DirectionMesh::cell_of(double x, double y) const {
    const int i = std::clamp(int((x - grid_min_) * grid_scale_), 0, kGrid - 1);
    const int j = std::clamp(int((y - grid_min_) * grid_scale_), 0, kGrid - 1);
    return j * kGrid + i;
}

// Precomputes each triangle's barycentric frame and each boundary edge, and lists per cell of a
// grid over the disk of all parabolic points the triangles and edges a query there may need.
void DirectionMesh::build_lookup() {
    double radius = 1;
    for (size_t i = 0; i < size(); ++i) radius = std::max(radius, std::hypot(px_[i], py_[i]));
    radius *= 1 + 1e-6;
    grid_min_ = -radius;
    grid_scale_ = kGrid / (2 * radius);
    for (size_t t = 0; t < triangles_.size(); t += 3) {
        const Point a{px_[triangles_[t]], py_[triangles_[t]]};
        const Point b{px_[triangles_[t + 1]], py_[triangles_[t + 1]]};
        const Point c{px_[triangles_[t + 2]], py_[triangles_[t + 2]]};
        const double m00 = b.x - a.x, m01 = c.x - a.x, m10 = b.y - a.y, m11 = c.y - a.y;
        const double inv_det = 1 / (m00 * m11 - m01 * m10);
        frames_.push_back(
            {a.x, a.y, {m11 * inv_det, -m01 * inv_det, -m10 * inv_det, m00 * inv_det}});
    }
    for (size_t e = 0; e < boundary_.size(); e += 2) {
        const uint32_t a = boundary_[e], b = boundary_[e + 1];
        const double dx = px_[b] - px_[a], dy = py_[b] - py_[a];
        edges_.push_back({px_[a], py_[a], dx, dy, 1 / (dx * dx + dy * dy)});
    }
    cell_triangles_.start.assign(1, 0);
    cell_edges_.start.assign(1, 0);
    for (int j = 0; j < kGrid; ++j)
        for (int i = 0; i < kGrid; ++i) fill_cell(i, j);
}

// Lists for cell (i, j) the triangles whose bounding box overlaps it, and the boundary edges
// that may be nearest to some point of it: an edge farther from the cell's centre than the
// nearest edge by more than the cell's diagonal is farther from every point of the cell.
void DirectionMesh::fill_cell(int i, int j) {
    const double cell = 1 / grid_scale_, slack = 1e-9;
    const double x0 = grid_min_ + i * cell - slack, x1 = x0 + cell + 2 * slack;
    const double y0 = grid_min_ + j * cell - slack, y1 = y0 + cell + 2 * slack;
    for (uint32_t t = 0; t < triangles_.size() / 3; ++t) {
        const uint32_t* v = &triangles_[3 * t];
        if (std::max({px_[v[0]], px_[v[1]], px_[v[2]]}) >= x0 &&
            std::min({px_[v[0]], px_[v[1]], px_[v[2]]}) <= x1 &&
            std::max({py_[v[0]], py_[v[1]], py_[v[2]]}) >= y0 &&
            std::min({py_[v[0]], py_[v[1]], py_[v[2]]}) <= y1)
            cell_triangles_.items.push_back(t);
    }
    cell_triangles_.start.push_back(uint32_t(cell_triangles_.items.size()));
    const double cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
    double nearest = std::numeric_limits<double>::infinity();
    std::vector<double> distances;
    for (size_t e = 0; e < boundary_.size(); e += 2) {
        distances.push_back(distance_to_segment(cx, cy, {px_[boundary_[e]], py_[boundary_[e]]},
                                                {px_[boundary_[e + 1]], py_[boundary_[e + 1]]}));
        nearest = std::min(nearest, distances.back());
    }
    for (uint32_t e = 0; e < distances.size(); ++e)
        if (distances[e] <= nearest + std::sqrt(2.) * (x1 - x0) + slack)
            cell_edges_.items.push_back(e);
    cell_edges_.start.push_back(uint32_t(cell_edges_.items.size()));
}

DirectionMesh::Weights DirectionMesh::triangle_weights(uint32_t t, const double bary[3]) const {
    // Clamp the rounding-sized negative coordinates of points on an edge, then renormalize.
    double b[3], sum = 0;
    for (int k = 0; k < 3; ++k) sum += b[k] = std::max(bary[k], 0.);
    Weights w;
    for (int k = 0; k < 3; ++k) {
        w.weight[k] = float(b[k] / sum);
        if (w.weight[k] > 0) w.index[k] = triangles_[3 * t + k];  // else index 0, as documented
    }
    return w;
}

// Outside the hull: the nearest point on the hull's boundary, linear along its edge.
DirectionMesh::Weights DirectionMesh::edge_weights(double x, double y, uint32_t cell) const {
    double best = std::numeric_limits<double>::infinity(), best_t = 0;
    uint32_t best_edge = 0;
    for (uint32_t k = cell_edges_.start[cell]; k < cell_edges_.start[cell + 1]; ++k) {
        const Edge& e = edges_[cell_edges_.items[k]];
        const double t =
            std::clamp(((x - e.ax) * e.dx + (y - e.ay) * e.dy) * e.inv_length2, 0., 1.);
        const double ex = x - e.ax - t * e.dx, ey = y - e.ay - t * e.dy;
        if (ex * ex + ey * ey < best)
            best = ex * ex + ey * ey, best_t = t, best_edge = cell_edges_.items[k];
    }
    Weights w;
    w.index[0] = boundary_[2 * best_edge];
    w.index[1] = boundary_[2 * best_edge + 1];
    w.weight[0] = float(1 - best_t);
    w.weight[1] = float(best_t);
    for (int k = 0; k < 2; ++k)
        if (w.weight[k] == 0) w.index[k] = 0;
    return w;
}

DirectionMesh::Weights DirectionMesh::interpolate(const Vec3& d) const {
    const auto [px, py] = parabolic(d);
    const uint32_t cell = uint32_t(cell_of(px, py));
    double best_bary[3] = {-1, 0, 0}, best_min = -std::numeric_limits<double>::infinity();
    uint32_t best_t = 0;
    for (uint32_t k = cell_triangles_.start[cell]; k < cell_triangles_.start[cell + 1]; ++k) {
        const TriangleFrame& f = frames_[cell_triangles_.items[k]];
        const double rx = px - f.ax, ry = py - f.ay;
        const double b1 = f.inverse[0] * rx + f.inverse[1] * ry;
        const double b2 = f.inverse[2] * rx + f.inverse[3] * ry;
        const double bary[3] = {1 - b1 - b2, b1, b2};
        const double lowest = std::min({bary[0], b1, b2});
        if (lowest >= 0) return triangle_weights(cell_triangles_.items[k], bary);
        if (lowest > best_min) {
            best_min = lowest;
            best_t = cell_triangles_.items[k];
            std::copy(bary, bary + 3, best_bary);
        }
    }
    // Points on an edge may miss every triangle by rounding (1e-9 is ~1e5 times that).
    if (best_min >= -1e-9) return triangle_weights(best_t, best_bary);
    return edge_weights(px, py, cell);
}

}  // namespace femto
