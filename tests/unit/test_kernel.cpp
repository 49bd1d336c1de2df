// Density-estimation kernels (femto/kernel.h) against quadrature, the progressive bandwidth
// schedules against their definitions (eq. 5.47, 5.58, 5.77-5.78), and the photons' grid
// (femto/point_grid.h) against brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "femto/kernel.h"
#include "femto/point_grid.h"
#include "femto/random.h"

using namespace femto;

namespace {

constexpr KernelShape kShapes[] = {KernelShape::Box, KernelShape::Epanechnikov, KernelShape::Perlin,
                                   KernelShape::Gaussian};

// Composite Simpson's rule of f over [a, b] with n (even) intervals.
template <typename F>
double simpson(F&& f, double a, double b, int n = 20000) {
    const double h = (b - a) / n;
    double s = f(a) + f(b);
    for (int i = 1; i < n; ++i) s += f(a + i * h) * (i % 2 ? 4 : 2);
    return s * h / 3;
}

// The profile with its value at |u| = 1 taken from inside (the box jumps to 0 there), as the
// integrals see it.
double profile(KernelShape shape, double u) {
    return kernel_profile(shape, std::clamp(u, -1.0 + 1e-12, 1.0 - 1e-12));
}

}  // namespace

TEST(Kernel, CdfIsTheIntegralOfTheNormalisedProfile) {
    for (KernelShape shape : kShapes) {
        SCOPED_TRACE(kernel_shape_name(shape));
        const double norm = kernel_ball_integral(shape, 1);
        EXPECT_EQ(kernel_cdf(shape, -1.0), 0.0);
        EXPECT_EQ(kernel_cdf(shape, 1.0), 1.0);
        EXPECT_EQ(kernel_profile(shape, 0.0), 1.0);
        EXPECT_EQ(kernel_profile(shape, 1.0), 0.0);
        for (double u : {-0.9, -0.5, -0.1, 0.0, 0.3, 0.77, 0.99}) {
            const double integral =
                simpson([&](double x) { return profile(shape, x); }, -1.0, u) / norm;
            EXPECT_NEAR(kernel_cdf(shape, u), integral, 1e-9) << "u = " << u;
        }
    }
}

TEST(Kernel, BallIntegralsMatchQuadrature) {
    // The unit ball's integral of profile(|x|): 2 int_0^1 p, 2 pi int_0^1 p r dr,
    // 4 pi int_0^1 p r^2 dr.
    for (KernelShape shape : kShapes) {
        SCOPED_TRACE(kernel_shape_name(shape));
        auto p = [&](double r) { return profile(shape, r); };
        const double one = 2 * simpson(p, 0, 1);
        const double two = 2 * M_PI * simpson([&](double r) { return p(r) * r; }, 0, 1);
        const double three = 4 * M_PI * simpson([&](double r) { return p(r) * r * r; }, 0, 1);
        EXPECT_NEAR(kernel_ball_integral(shape, 1), one, 1e-9);
        EXPECT_NEAR(kernel_ball_integral(shape, 2), two, 1e-9);
        EXPECT_NEAR(kernel_ball_integral(shape, 3), three, 1e-9);
    }
    EXPECT_THROW(kernel_ball_integral(KernelShape::Box, 4), std::invalid_argument);
}

TEST(Kernel, BinWeightsAreTheKernelMassInEachBin) {
    TimeGrid grid;  // [2, 7)
    grid.start = 2.0, grid.bin_width = 0.1, grid.bins = 50;
    for (KernelShape shape : kShapes) {
        SCOPED_TRACE(kernel_shape_name(shape));
        for (double t : {2.03, 4.5, 6.99, 7.2}) {
            const double T = 0.37;
            double sum = 0;
            int previous = -1;
            const double inside = integrate_over_bins(grid, shape, t, T, [&](int bin, double w) {
                EXPECT_GT(bin, previous);  // in bin order, each once
                previous = bin;
                const double lo = grid.start + bin * grid.bin_width, hi = lo + grid.bin_width;
                EXPECT_NEAR(w, kernel_cdf(shape, (hi - t) / T) - kernel_cdf(shape, (lo - t) / T),
                            1e-12);
                sum += w;
            });
            EXPECT_NEAR(sum, inside, 1e-12);
            const double expected =
                kernel_cdf(shape, (grid.end() - t) / T) - kernel_cdf(shape, (grid.start - t) / T);
            EXPECT_NEAR(inside, expected, 1e-12) << "t = " << t;
        }
    }
}

TEST(Kernel, ProgressiveShrinkIsTheProductOfEq547) {
    for (double alpha : {0.2, 4.0 / 7.0, 0.8}) {
        double product = 1.0;
        for (uint64_t j = 0; j < 2000; ++j) {
            if (j > 0) product *= (double(j) + alpha) / (double(j) + 1.0);
            ASSERT_NEAR(progressive_shrink(alpha, j), product, 1e-10 * product) << "j = " << j;
        }
    }
}

TEST(Kernel, PhotonMappingScheduleFollowsEq558) {
    // R_{j+1}^2 / R_j^2 = ((j + alpha) / (j + 1))^beta_R and T_{j+1} / T_j = (...)^beta_T,
    // beta_R = 1 - beta_T, for iterations j = 1, 2, ... (iteration index j - 1); and the
    // closed forms of eq. 5.77-5.78, T_j = T_1 (j alpha B(alpha, j))^-beta_T.
    const ProgressiveBandwidths schedule{4.0 / 7.0, 1.0 / 3.0};
    const double r1 = 0.25, t1 = 0.1;
    for (uint64_t j = 1; j < 100000; j = j < 16 ? j + 1 : j * 3) {
        const double ratio = (double(j) + schedule.alpha) / (double(j) + 1.0);
        const double r2 = schedule.radius_squared(r1 * r1, j - 1),
                     r2_next = schedule.radius_squared(r1 * r1, j);
        const double t = schedule.time(t1, j - 1), t_next = schedule.time(t1, j);
        // The closed form goes through lgamma(j) ~ j ln j, whose rounding (a few ulps of it)
        // becomes the relative error of the schedule.
        const double tol = 16 * 2.2e-16 * (double(j) + 1) * std::log(double(j) + 2);
        EXPECT_NEAR(r2_next / r2, std::pow(ratio, 2.0 / 3.0), tol) << "j = " << j;
        EXPECT_NEAR(t_next / t, std::pow(ratio, 1.0 / 3.0), tol) << "j = " << j;
        // Each iteration scales the variance (1 / (R^2 T)) by (j + 1) / (j + alpha) (eq. 5.57).
        EXPECT_NEAR((r2 * t) / (r2_next * t_next), 1.0 / ratio, 2 * tol);
        const double a = schedule.alpha, jd = double(j);
        const double beta = std::exp(std::lgamma(a) + std::lgamma(jd) - std::lgamma(a + jd));
        EXPECT_NEAR(t / t1, std::pow(jd * a * beta, -1.0 / 3.0), tol * (t / t1));
        EXPECT_NEAR(r2 / (r1 * r1), std::pow(jd * a * beta, -2.0 / 3.0), tol * r2 / (r1 * r1));
    }
    EXPECT_EQ(schedule.radius_squared(r1 * r1, 0), r1 * r1);
    EXPECT_EQ(schedule.time(t1, 0), t1);
}

TEST(Kernel, VolumetricScheduleShrinksTheBallVolume) {
    // In 3D the kernel's volume R^3 takes the share beta_R of each iteration's reduction: with
    // alpha 1/2 and beta_T 1/4, R_{j+1}^3 / R_j^3 = ((j + alpha) / (j + 1))^(3/4), and R^3 T
    // shrinks by (j + alpha) / (j + 1).
    const ProgressiveBandwidths schedule{0.5, 0.25, 3};
    const double r1 = 0.25, t1 = 0.1;
    for (uint64_t j = 1; j < 100000; j = j < 16 ? j + 1 : j * 3) {
        const double ratio = (double(j) + 0.5) / (double(j) + 1.0);
        const double r3 = std::pow(schedule.radius_squared(r1 * r1, j - 1), 1.5),
                     r3_next = std::pow(schedule.radius_squared(r1 * r1, j), 1.5);
        const double t = schedule.time(t1, j - 1), t_next = schedule.time(t1, j);
        const double tol = 16 * 2.2e-16 * (double(j) + 1) * std::log(double(j) + 2);
        EXPECT_NEAR(r3_next / r3, std::pow(ratio, 0.75), tol) << "j = " << j;
        EXPECT_NEAR(t_next / t, std::pow(ratio, 0.25), tol) << "j = " << j;
        EXPECT_NEAR((r3_next * t_next) / (r3 * t), ratio, 2 * tol) << "j = " << j;
    }
}

TEST(PointGrid, VisitsEveryPointWithinTheRadiusOnce) {
    // Random points in a box that straddles the origin (negative cells), queries at random
    // places and on points themselves: the grid must visit every point within the radius, each
    // once, for the caller to keep those within it.
    Pcg32 rng(7, 3);
    auto uniform = [&](float lo, float hi) { return lo + (hi - lo) * rng.next_float(); };
    std::vector<Vec3> points;
    for (int i = 0; i < 5000; ++i)
        points.push_back({uniform(-3.f, 2.f), uniform(-1.f, 1.f), uniform(-0.5f, 4.f)});
    for (float radius : {0.05f, 0.3f, 1.5f}) {
        PointGrid grid;
        grid.build(points, radius);
        for (int q = 0; q < 200; ++q) {
            const Vec3 x =
                q % 4 == 0 ? points[size_t(q)]
                           : Vec3{uniform(-3.5f, 2.5f), uniform(-1.5f, 1.5f), uniform(-1.f, 4.5f)};
            std::vector<int> visits(points.size(), 0);
            grid.query(x, [&](uint32_t i) { ++visits[i]; });
            for (size_t i = 0; i < points.size(); ++i) {
                const Vec3 d = points[i] - x;
                ASSERT_LE(visits[i], 1) << "point " << i << " visited twice";
                if (dot(d, d) <= radius * radius) {
                    ASSERT_EQ(visits[i], 1) << "point " << i << " within " << radius << " missed";
                }
            }
        }
    }
    PointGrid empty;
    empty.build({}, 1.f);
    int visited = 0;
    empty.query(Vec3(0.f), [&](uint32_t) { ++visited; });
    EXPECT_EQ(visited, 0);
}
