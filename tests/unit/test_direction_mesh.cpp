// DirectionMesh (femto/direction_mesh.h): the triangulation of the Bonn BTF samplings (UBO2003,
// 81 directions; UBO2014, 151) and of random directions is a valid Delaunay triangulation of
// their convex hull in the parabolic map, and interpolation is exact at the samples, a
// partition of unity everywhere, linear where it should be, continuous, and projects grazing
// directions onto the outer ring. Bad input names the direction at fault.
//
// Tolerances: the weights are floats, so a weight carries a rounding of ~6e-8 and a sum of
// three ~2e-7; 1e-6 allows a few such roundings. Geometry is checked in double on the
// parabolic coordinates of the float directions, where only double rounding (~1e-16) enters,
// so 1e-9 (relative) separates rounding from real errors by many orders of magnitude.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "femto/direction_mesh.h"

namespace {

using femto::DirectionMesh;
using femto::Vec3;

struct P2 {
    double x, y;
};

Vec3 direction(double theta_deg, double phi_deg) {
    const double t = theta_deg * M_PI / 180, p = phi_deg * M_PI / 180;
    return Vec3(float(std::sin(t) * std::cos(p)), float(std::sin(t) * std::sin(p)),
                float(std::cos(t)));
}

std::vector<Vec3> rings(const std::vector<double>& theta, const std::vector<int>& count,
                        const std::vector<double>& offset) {
    std::vector<Vec3> dirs;
    for (size_t r = 0; r < theta.size(); ++r)
        for (int j = 0; j < count[r]; ++j)
            dirs.push_back(direction(theta[r], offset[r] + 360.0 * j / count[r]));
    return dirs;
}

std::vector<Vec3> ubo2003() {
    return rings({0, 15, 30, 45, 60, 75}, {1, 6, 12, 18, 20, 24}, {0, 0, 0, 0, 0, 0});
}

std::vector<Vec3> ubo2014() {
    return rings({0, 11, 23.5, 30, 37.5, 45, 52.5, 60, 67.5, 75},
                 {1, 6, 12, 12, 12, 18, 18, 24, 24, 24}, {0, 15, 0, 15, 0, 0, 7.5, 0, 7.5, 0});
}

// Uniform over the upper hemisphere (fixed seed), as a less regular test of the triangulation.
std::vector<Vec3> random_upper(int n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    std::vector<Vec3> dirs;
    for (int i = 0; i < n; ++i)
        dirs.push_back(direction(std::acos(u(rng)) * 180 / M_PI, 360 * u(rng)));
    return dirs;
}

// Uniform over the whole sphere, as float directions.
Vec3 random_sphere(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(0, 1);
    return direction(std::acos(1 - 2 * u(rng)) * 180 / M_PI, 360 * u(rng));
}

// (x, y) / (1 + z), written (x, y) / (|d| + z) as DirectionMesh does, so that the float
// directions, whose lengths differ from 1 by ~1e-7, map where the mesh maps them.
P2 parabolic(const Vec3& d) {
    const double len = std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z);
    return {d.x / (len + d.z), d.y / (len + d.z)};
}

double orient(P2 a, P2 b, P2 c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }

double hull_area(std::vector<P2> pts) {
    std::sort(pts.begin(), pts.end(),
              [](P2 a, P2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
    std::vector<P2> lower, upper;
    for (const P2& p : pts) {
        while (lower.size() >= 2 && orient(lower[lower.size() - 2], lower.back(), p) <= 0)
            lower.pop_back();
        lower.push_back(p);
    }
    for (auto it = pts.rbegin(); it != pts.rend(); ++it) {
        while (upper.size() >= 2 && orient(upper[upper.size() - 2], upper.back(), *it) <= 0)
            upper.pop_back();
        upper.push_back(*it);
    }
    lower.pop_back();
    upper.pop_back();
    lower.insert(lower.end(), upper.begin(), upper.end());
    double area = 0;
    for (size_t i = 0; i < lower.size(); ++i)
        area += orient(lower[0], lower[i], lower[(i + 1) % lower.size()]);
    return area / 2;
}

double interpolate(const DirectionMesh& mesh, const std::vector<double>& values, const Vec3& d) {
    const DirectionMesh::Weights w = mesh.interpolate(d);
    return w.weight[0] * values[w.index[0]] + w.weight[1] * values[w.index[1]] +
           w.weight[2] * values[w.index[2]];
}

struct Sampling {
    const char* name;
    std::vector<Vec3> dirs;
};

std::vector<Sampling> samplings() {
    return {{"UBO2003", ubo2003()}, {"UBO2014", ubo2014()}, {"random200", random_upper(200, 7)}};
}

TEST(DirectionMesh, BonnSamplingSizesAndTriangleCounts) {
    const DirectionMesh a(ubo2003()), b(ubo2014());
    EXPECT_EQ(a.size(), 81u);
    EXPECT_EQ(b.size(), 151u);
    // Euler: a triangulation of n points with h on the hull has 2n - 2 - h triangles, and both
    // samplings have the 24 directions at 75 degrees on the hull.
    EXPECT_EQ(a.triangles().size() / 3, 2 * 81u - 2 - 24);
    EXPECT_EQ(b.triangles().size() / 3, 2 * 151u - 2 - 24);
    EXPECT_EQ(a.boundary_edges().size() / 2, 24u);
    EXPECT_EQ(b.boundary_edges().size() / 2, 24u);
}

TEST(DirectionMesh, ExactAtTheSamples) {
    for (const Sampling& s : samplings()) {
        const DirectionMesh mesh(s.dirs);
        for (uint32_t i = 0; i < s.dirs.size(); ++i) {
            const DirectionMesh::Weights w = mesh.interpolate(s.dirs[i]);
            double on_sample = 0, elsewhere = 0;
            for (int k = 0; k < 3; ++k) (w.index[k] == i ? on_sample : elsewhere) += w.weight[k];
            EXPECT_NEAR(on_sample, 1, 1e-6) << s.name << " direction " << i;
            EXPECT_NEAR(elsewhere, 0, 1e-6) << s.name << " direction " << i;
        }
    }
}

TEST(DirectionMesh, ValidDelaunayTriangulationOfTheHull) {
    for (const Sampling& s : samplings()) {
        const DirectionMesh mesh(s.dirs);
        std::vector<P2> p;
        for (const Vec3& d : s.dirs) p.push_back(parabolic(d));
        const std::vector<uint32_t>& tris = mesh.triangles();
        ASSERT_EQ(tris.size() % 3, 0u);
        std::vector<int> used(p.size(), 0);
        double area = 0;
        for (size_t t = 0; t < tris.size(); t += 3) {
            const P2 a = p[tris[t]], b = p[tris[t + 1]], c = p[tris[t + 2]];
            const double twice_area = orient(a, b, c);
            EXPECT_GT(twice_area, 0) << s.name << " triangle " << t / 3;
            area += twice_area / 2;
            for (int k = 0; k < 3; ++k) used[tris[t + k]] = 1;
            // Circumcircle; no sample strictly inside it (cocircular ones lie on it to rounding).
            const double bx = b.x - a.x, by = b.y - a.y, cx = c.x - a.x, cy = c.y - a.y;
            const double d = 2 * (bx * cy - by * cx);
            const double ux = (cy * (bx * bx + by * by) - by * (cx * cx + cy * cy)) / d;
            const double uy = (bx * (cx * cx + cy * cy) - cx * (bx * bx + by * by)) / d;
            const double r = std::hypot(ux, uy);
            for (size_t q = 0; q < p.size(); ++q)
                EXPECT_GE(std::hypot(p[q].x - a.x - ux, p[q].y - a.y - uy), r * (1 - 1e-9))
                    << s.name << ": direction " << q << " inside the circumcircle of triangle "
                    << t / 3;
        }
        EXPECT_NEAR(area, hull_area(p), 1e-9 * hull_area(p)) << s.name;
        EXPECT_EQ(std::count(used.begin(), used.end(), 1), long(p.size())) << s.name;
    }
}

TEST(DirectionMesh, WeightsArePartitionOfUnityOverTheWholeSphere) {
    std::mt19937 rng(12345);
    for (const Sampling& s : samplings()) {
        const DirectionMesh mesh(s.dirs);
        for (int i = 0; i < 100000; ++i) {
            const Vec3 d = random_sphere(rng);
            const DirectionMesh::Weights w = mesh.interpolate(d);
            double sum = 0;
            for (int k = 0; k < 3; ++k) {
                ASSERT_GE(w.weight[k], 0.f) << s.name;
                ASSERT_LT(w.index[k], s.dirs.size()) << s.name;
                if (w.weight[k] == 0) {
                    ASSERT_EQ(w.index[k], 0u) << s.name;
                }
                sum += w.weight[k];
            }
            ASSERT_NEAR(sum, 1, 1e-6)
                << s.name << " at (" << d.x << ", " << d.y << ", " << d.z << ")";
        }
    }
}

TEST(DirectionMesh, ReproducesFunctionsLinearInTheParabolicMap) {
    std::mt19937 rng(99);
    std::uniform_real_distribution<double> u(0, 1);
    for (const Sampling& s : {samplings()[0], samplings()[1]}) {
        const DirectionMesh mesh(s.dirs);
        auto f = [](P2 p) { return 0.5 + 1.5 * p.x - 2.0 * p.y; };
        std::vector<double> values;
        for (const Vec3& d : s.dirs) values.push_back(f(parabolic(d)));
        // Up to 70 degrees: inside the 24-gon of the 75-degree ring (inradius
        // tan(37.5) cos(7.5) = 0.761 > tan(35) = 0.700 in the parabolic map).
        for (int i = 0; i < 20000; ++i) {
            const Vec3 d = direction(
                std::acos(1 - u(rng) * (1 - std::cos(70 * M_PI / 180))) * 180 / M_PI, 360 * u(rng));
            ASSERT_NEAR(interpolate(mesh, values, d), f(parabolic(d)), 1e-5) << s.name;
        }
    }
}

// The largest gradient, in the parabolic map, of the piecewise-linear interpolant of `values`.
double lipschitz_constant(const DirectionMesh& mesh, const std::vector<double>& values) {
    double most = 0;
    const std::vector<uint32_t>& tris = mesh.triangles();
    for (size_t t = 0; t < tris.size(); t += 3) {
        const P2 a = parabolic(mesh.directions()[tris[t]]),
                 b = parabolic(mesh.directions()[tris[t + 1]]),
                 c = parabolic(mesh.directions()[tris[t + 2]]);
        const double fb = values[tris[t + 1]] - values[tris[t]],
                     fc = values[tris[t + 2]] - values[tris[t]];
        const double det = orient(a, b, c);
        const double gx = (fb * (c.y - a.y) - fc * (b.y - a.y)) / det;
        const double gy = (fc * (b.x - a.x) - fb * (c.x - a.x)) / det;
        most = std::max(most, std::hypot(gx, gy));
    }
    return most;
}

TEST(DirectionMesh, ContinuousEverywhere) {
    // Bound: on the upper hemisphere the parabolic map shrinks distances (its derivative is
    // 1 / (1 + cos theta) <= 1), so two directions an angle a apart map less than a apart. Below
    // the horizon a direction maps to the horizon point of its azimuth, which moves by at most
    // a / sin(theta). Projecting onto the convex hull shrinks distances too, and along a hull
    // edge the interpolant's slope is at most that of the triangle on the edge. So the value
    // changes by at most L a / min(1, sin theta), L the interpolant's largest gradient, plus
    // the float rounding of the weights.
    std::mt19937 rng(2024);
    std::uniform_real_distribution<double> u(0, 1);
    for (const Sampling& s : samplings()) {
        const DirectionMesh mesh(s.dirs);
        std::vector<double> values;
        for (const Vec3& d : s.dirs) values.push_back(d.x + 2.0 * d.y + double(d.z) * d.z);
        const double lipschitz = lipschitz_constant(mesh, values), step = 1e-4;
        for (int i = 0; i < 100000; ++i) {
            const Vec3 a = random_sphere(rng);
            // b: a turned by `step` about a random axis perpendicular to a.
            const femto::Frame frame(a);
            const double angle = 2 * M_PI * u(rng);
            const Vec3 t = frame.s * float(std::cos(angle)) + frame.t * float(std::sin(angle));
            const Vec3 b = a * float(std::cos(step)) + t * float(std::sin(step));
            const double sin_theta = std::min(std::hypot(a.x, a.y), std::hypot(b.x, b.y)) - step;
            if (sin_theta < 1e-2) continue;  // next to the nadir, where no bound holds
            const double stretch = (a.z < 0 || b.z < 0) ? 1 / std::min(1.0, sin_theta) : 1.0;
            // 1.01 and 1e-6: the float rounding of b's construction and of the weights.
            const double bound = 1.01 * lipschitz * step * stretch + 1e-6;
            ASSERT_LE(std::abs(interpolate(mesh, values, a) - interpolate(mesh, values, b)), bound)
                << s.name << " at (" << a.x << ", " << a.y << ", " << a.z << ")";
        }
    }
}

TEST(DirectionMesh, GrazingDirectionsUseTheOuterRingsNearestEdge) {
    for (const Sampling& s : {samplings()[0], samplings()[1]}) {
        const DirectionMesh mesh(s.dirs);
        const size_t outer_first = s.dirs.size() - 24;  // the 24 directions at 75 degrees
        for (int k = 0; k < 720; ++k) {
            const Vec3 d = direction(85, 0.5 * k + 0.1);
            const DirectionMesh::Weights w = mesh.interpolate(d);
            int non_zero = 0;
            for (int j = 0; j < 3; ++j)
                if (w.weight[j] > 0) {
                    ++non_zero;
                    EXPECT_GE(w.index[j], outer_first) << s.name << " azimuth " << 0.5 * k;
                }
            EXPECT_LE(non_zero, 2);
            // Expected: the nearest point on the outer ring's polygon.
            const P2 p = parabolic(d);
            double best = 1e300, best_t = 0;
            size_t best_j = 0;
            for (size_t j = 0; j < 24; ++j) {
                const P2 a = parabolic(s.dirs[outer_first + j]),
                         b = parabolic(s.dirs[outer_first + (j + 1) % 24]);
                const double dx = b.x - a.x, dy = b.y - a.y;
                const double t = std::clamp(
                    ((p.x - a.x) * dx + (p.y - a.y) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
                const double dist = std::hypot(p.x - a.x - t * dx, p.y - a.y - t * dy);
                if (dist < best) best = dist, best_t = t, best_j = j;
            }
            std::vector<double> expected(s.dirs.size(), 0), got(s.dirs.size(), 0);
            expected[outer_first + best_j] += 1 - best_t;
            expected[outer_first + (best_j + 1) % 24] += best_t;
            for (int j = 0; j < 3; ++j) got[w.index[j]] += w.weight[j];
            for (size_t j = 0; j < s.dirs.size(); ++j)
                EXPECT_NEAR(got[j], expected[j], 1e-6) << s.name << " azimuth " << 0.5 * k;
        }
    }
}

TEST(DirectionMesh, BelowTheHorizonIsClampedToIt) {
    const DirectionMesh mesh(ubo2014());
    for (int k = 0; k < 36; ++k) {
        const DirectionMesh::Weights below = mesh.interpolate(direction(120, 10.0 * k + 3));
        const DirectionMesh::Weights horizon = mesh.interpolate(direction(90, 10.0 * k + 3));
        for (int j = 0; j < 3; ++j) {
            EXPECT_EQ(below.index[j], horizon.index[j]);
            EXPECT_NEAR(below.weight[j], horizon.weight[j], 1e-6);
        }
    }
}

void expect_invalid(std::vector<Vec3> dirs, const std::vector<std::string>& mentions) {
    try {
        DirectionMesh mesh(std::move(dirs));
        ADD_FAILURE() << "no exception; expected one mentioning " << mentions[0];
    } catch (const std::invalid_argument& e) {
        for (const std::string& m : mentions)
            EXPECT_NE(std::string(e.what()).find(m), std::string::npos) << e.what();
    }
}

TEST(DirectionMesh, BadInputNamesTheDirection) {
    const std::vector<Vec3> good = ubo2003();
    expect_invalid({good[0], good[1]}, {"at least 3", "got 2"});
    auto with = [&](size_t i, Vec3 d) {
        std::vector<Vec3> dirs = good;
        dirs[i] = d;
        return dirs;
    };
    expect_invalid(with(4, Vec3(NAN, 0, 1)), {"direction 4 ", "not finite"});
    expect_invalid(with(5, Vec3(0, INFINITY, 0)), {"direction 5 ", "not finite"});
    expect_invalid(with(6, direction(30, 17) * 1.01f), {"direction 6 ", "unit"});
    expect_invalid(with(7, Vec3(0.99999f, 0, -0.005f)), {"direction 7 ", "horizon"});
    expect_invalid(with(9, good[3] + Vec3(3e-6f, 0, 0)),
                   {"direction 9 ", "direction 3 ", "closer"});
    std::vector<Vec3> meridian;  // all in the plane y = 0: a line in the parabolic map
    for (int k = -5; k <= 5; ++k)
        meridian.push_back(direction(std::abs(15.0 * k), k < 0 ? 180 : 0));
    expect_invalid(meridian, {"collinear", "directions 0 and"});
    // Within the tolerances: slightly below the horizon, slightly off unit length.
    EXPECT_NO_THROW(DirectionMesh(with(80, Vec3(0.5f, 0.8660254f, -5e-7f))));
    EXPECT_NO_THROW(DirectionMesh(with(10, direction(30, 17) * 1.0005f)));
}

TEST(DirectionMesh, NonFiniteQueryDoesNotCrash) {
    const DirectionMesh mesh(ubo2003());
    for (const Vec3& d : {Vec3(NAN, 0, 1), Vec3(0, 0, 0), Vec3(0, 0, -1), Vec3(INFINITY, 1, 0)}) {
        const DirectionMesh::Weights w = mesh.interpolate(d);
        EXPECT_NEAR(w.weight[0] + w.weight[1] + w.weight[2], 1, 1e-6);
    }
}

}  // namespace
