// Tests of the `heterogeneous` medium plugin: Mitsuba .vol grids written to a temporary folder,
// trilinear lookups, transmittance by (residual) ratio tracking against analytic optical
// depths (constant grids, a linear ramp, a transformed box), and every malformed file giving a
// SceneError that names the file.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "femto/error.h"
#include "femto/host.h"
#include "femto/medium.h"
#include "femto/random.h"
#include "femto/sampler.h"
#include "femto/scene.h"
#include "femto/shape.h"
#include "femto/transform.h"
#include "scene_util.h"
#include "vol_util.h"

namespace {

namespace fs = std::filesystem;
using femto::Color;
using femto::Medium;
using femto::PluginKind;
using femto::Properties;
using femto::Ray;
using femto::Vec3;

// ---------------------------------------------------------------------------------------------
// Helpers

/// A Sampler drawing from Pcg32 that counts how many numbers were drawn.
class CountingSampler final : public femto::Sampler {
public:
    explicit CountingSampler(uint64_t seed) : rng_(seed, 0x5bd1e995) {}
    std::unique_ptr<femto::Sampler> clone() const override {
        return std::make_unique<CountingSampler>(*this);
    }
    void start(uint64_t seed, uint64_t pixel, uint32_t sample) override {
        rng_ = femto::Pcg32(seed ^ (uint64_t(sample) << 40), pixel);
    }
    float next_1d() override {
        ++draws;
        return rng_.next_float();
    }
    femto::Vec2 next_2d() override {
        draws += 2;
        return {rng_.next_float(), rng_.next_float()};
    }
    uint64_t draws = 0;

private:
    femto::Pcg32 rng_;
};

using femto::test::make_grid;
using femto::test::VolFile;
using femto::test::write_bytes;

const femto::SourceLocation kDensityLoc{"media.xml", 3, 4};

Properties medium_props(const fs::path& file) {
    Properties props("heterogeneous", {"media.xml", 2, 1});
    props.set("density", Properties::Type::String, file.string(), kDensityLoc);
    return props;
}

std::shared_ptr<Medium> make_medium(const Properties& props) {
    femto::ObjectPtr obj = femto::create_object(PluginKind::Medium, "heterogeneous", props);
    EXPECT_TRUE(obj);
    EXPECT_EQ(obj->kind(), PluginKind::Medium);
    return std::static_pointer_cast<Medium>(obj);
}

std::shared_ptr<Medium> make_medium(const fs::path& file, double scale = 1.0) {
    Properties props = medium_props(file);
    props.set_float("scale", scale);
    return make_medium(props);
}

struct Estimate {
    double mean = 0, se = 0;
    double min = 1, max = 0;
    uint64_t draws = 0;
};

/// Mean and standard error of n transmittance estimates (all three channels must agree).
Estimate estimate(const Medium& m, const Ray& ray, double distance, int n, uint64_t seed) {
    CountingSampler s(seed);
    double sum = 0, sum2 = 0;
    Estimate e;
    for (int i = 0; i < n; ++i) {
        const Color t = m.transmittance(ray, distance, s);
        EXPECT_EQ(t.r, t.g);
        EXPECT_EQ(t.r, t.b);
        EXPECT_TRUE(t.r >= 0.f && t.r <= 1.f) << t.r;
        sum += t.r;
        sum2 += double(t.r) * t.r;
        e.min = std::min(e.min, double(t.r));
        e.max = std::max(e.max, double(t.r));
    }
    e.mean = sum / n;
    e.se = std::sqrt(std::max(0.0, sum2 / n - e.mean * e.mean) / (n - 1));
    e.draws = s.draws;
    return e;
}

Ray make_ray(Vec3 o, Vec3 d) {
    Ray r;
    r.o = o;
    r.d = femto::normalize(d);
    return r;
}

double norm(Vec3 v) { return std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z); }

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------
// Lookups

double ref_value(int x, int y, int z) { return ((x * 7 + y * 13 + z * 29) % 11) * 0.37 + 0.1; }

TEST(Heterogeneous, TrilinearLookupsAtDataPointsAndMidpoints) {
    const auto dir = femto::test::temp_dir("het-lookup");
    // 3 x 4 x 5 points over [-1, 1] x [0, 3] x [2, 6]: point (i, j, k) at (-1 + i, j, 2 + k).
    const VolFile v = make_grid(3, 4, 5, {-1, 0, 2}, {1, 3, 6}, ref_value);
    write_bytes(dir / "grid.vol", v.bytes());
    Properties props = medium_props(dir / "grid.vol");
    props.set_float("scale", 2.5);
    props.set_color("albedo", Color(0.2f, 0.5f, 0.9f));
    auto m = make_medium(props);
    ASSERT_TRUE(m);
    EXPECT_FALSE(m->homogeneous());
    EXPECT_EQ(m->eta(), 1.0);
    EXPECT_EQ(m->phase().type_name(), "isotropic");

    auto pos = [](double i, double j, double k) {
        return Vec3(float(-1 + i), float(j), float(2 + k));
    };
    auto expect_sigma = [&](Vec3 p, double density) {
        const Color st = m->sigma_t(p);
        const double expected = 2.5 * density;
        EXPECT_NEAR(st.r, expected, 1e-6 * expected + 1e-7) << p.x << " " << p.y << " " << p.z;
        EXPECT_EQ(st.r, st.g);
        EXPECT_EQ(st.r, st.b);
        const Color ss = m->sigma_s(p);
        EXPECT_FLOAT_EQ(ss.r, 0.2f * st.r);
        EXPECT_FLOAT_EQ(ss.g, 0.5f * st.r);
        EXPECT_FLOAT_EQ(ss.b, 0.9f * st.r);
    };
    double max_value = 0;
    for (int k = 0; k < 5; ++k)
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 3; ++i) {
                max_value = std::max(max_value, ref_value(i, j, k));
                expect_sigma(pos(i, j, k), ref_value(i, j, k));  // data points (incl. faces)
                if (i + 1 < 3)
                    expect_sigma(pos(i + 0.5, j, k),
                                 0.5 * (ref_value(i, j, k) + ref_value(i + 1, j, k)));
                if (j + 1 < 4)
                    expect_sigma(pos(i, j + 0.5, k),
                                 0.5 * (ref_value(i, j, k) + ref_value(i, j + 1, k)));
                if (k + 1 < 5)
                    expect_sigma(pos(i, j, k + 0.5),
                                 0.5 * (ref_value(i, j, k) + ref_value(i, j, k + 1)));
                if (i + 1 < 3 && j + 1 < 4 && k + 1 < 5) {
                    double sum = 0;
                    for (int c = 0; c < 8; ++c)
                        sum += ref_value(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
                    expect_sigma(pos(i + 0.5, j + 0.5, k + 0.5), sum / 8);  // cell centres
                }
            }
    EXPECT_NEAR(m->majorant(), 2.5 * max_value, 1e-6 * max_value);

    // A general point against trilinear interpolation written out here.
    femto::Pcg32 rng(1, 2);
    for (int n = 0; n < 200; ++n) {
        const double gx = 2 * rng.next_double(), gy = 3 * rng.next_double(),
                     gz = 4 * rng.next_double();
        const int i = std::min(int(gx), 1), j = std::min(int(gy), 2), k = std::min(int(gz), 3);
        const double fx = gx - i, fy = gy - j, fz = gz - k;
        double ref = 0;
        for (int c = 0; c < 8; ++c) {
            const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
            ref += ref_value(i + dx, j + dy, k + dz) * (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) *
                   (dz ? fz : 1 - fz);
        }
        const Vec3 p = pos(gx, gy, gz);
        // p is rounded to float: allow the density's change over that rounding.
        EXPECT_NEAR(m->sigma_t(p).r, 2.5 * ref, 1e-5) << gx << " " << gy << " " << gz;
    }

    // Zero outside the box, just past every face.
    const float eps = 1e-3f;
    for (Vec3 p : {Vec3(-1 - eps, 1, 3), Vec3(1 + eps, 1, 3), Vec3(0, -eps, 3), Vec3(0, 3 + eps, 3),
                   Vec3(0, 1, 2 - eps), Vec3(0, 1, 6 + eps)})
        EXPECT_EQ(m->sigma_t(p).r, 0.f) << p.x << " " << p.y << " " << p.z;
    EXPECT_EQ(m->sigma_s(Vec3(5, 5, 5)).g, 0.f);
    fs::remove_all(dir);
}

TEST(Heterogeneous, SinglePointAxesAreConstant) {
    const auto dir = femto::test::temp_dir("het-flat");
    const VolFile v =
        make_grid(3, 1, 1, {0, 0, 0}, {2, 1, 1}, [](int x, int, int) { return 1.0 + x; });
    write_bytes(dir / "flat.vol", v.bytes());
    auto m = make_medium(dir / "flat.vol");
    for (float y : {0.f, 0.3f, 1.f})
        for (float z : {0.f, 0.6f, 1.f}) {
            EXPECT_NEAR(m->sigma_t({0.5f, y, z}).r, 1.5f, 1e-6f);
            EXPECT_NEAR(m->sigma_t({2.f, y, z}).r, 3.f, 1e-6f);
        }
    EXPECT_EQ(m->sigma_t({1.f, 1.5f, 0.5f}).r, 0.f);
    fs::remove_all(dir);
}

TEST(Heterogeneous, ReadsEtaAndNestedPhase) {
    const auto dir = femto::test::temp_dir("het-phase");
    write_bytes(dir / "g.vol", make_grid(2, 2, 2, {0, 0, 0}, {1, 1, 1}, [](int, int, int) {
                                   return 1.0;
                               }).bytes());
    Properties hg_props("hg", {});
    hg_props.set_float("g", 0.7);
    femto::ObjectPtr hg = femto::create_object(PluginKind::Phase, "hg", hg_props);
    Properties props = medium_props(dir / "g.vol");
    props.set_float("eta", 1.33);
    props.set_object("phase", hg);
    auto m = make_medium(props);
    EXPECT_DOUBLE_EQ(m->eta(), 1.33);
    EXPECT_EQ(&m->phase(), hg.get());
    fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Transmittance

TEST(Heterogeneous, ConstantGridIsExact) {
    const auto dir = femto::test::temp_dir("het-const");
    // Box [0, 1] x [0, 2] x [0, 3], density 2 everywhere.
    write_bytes(dir / "c.vol", make_grid(4, 3, 5, {0, 0, 0}, {1, 2, 3}, [](int, int, int) {
                                   return 2.0;
                               }).bytes());
    auto m = make_medium(dir / "c.vol", 0.75);  // sigma_t = 1.5
    EXPECT_FLOAT_EQ(m->majorant(), 1.5f);
    struct Case {
        Vec3 o, d;
        double distance, length;  ///< length of the ray inside the box
    };
    const Vec3 oblique(1, 0.5, 0.8);  // from (-1, 0.2, 0.4): x 0..1 inside the box
    const Case cases[] = {
        {{-1, 0.5, 1}, {1, 0, 0}, kInf, 1.0},            // through the box
        {{-1, 0.5, 1}, {1, 0, 0}, 1.4, 0.4},             // ends inside
        {{0.5, 1, 1}, {0, -1, 0}, kInf, 1.0},            // starts inside
        {{0.5, 1, 1}, {0, 0, 1}, 0.5, 0.5},              // inside throughout
        {{-1, 0.2, 0.4}, oblique, kInf, norm(oblique)},  // oblique, x from 0 to 1
        {{-1, 0.2, 0.4}, oblique, 1.5 * norm(oblique), 0.5 * norm(oblique)},
    };
    for (const Case& c : cases) {
        const Ray ray = make_ray(c.o, c.d);
        const Estimate e = estimate(*m, ray, c.distance, 100, 1);
        const double expected = std::exp(-1.5 * c.length);
        EXPECT_NEAR(e.mean, expected, 1e-6 * expected) << c.o.x << " " << c.distance;
        EXPECT_EQ(e.min, e.max) << "a constant grid's transmittance has no variance";
        EXPECT_EQ(e.draws, 0u) << "no random numbers needed";
    }
    fs::remove_all(dir);
}

TEST(Heterogeneous, OutsideTheBoxIsExactlyOne) {
    const auto dir = femto::test::temp_dir("het-outside");
    write_bytes(dir / "r.vol", make_grid(3, 3, 3, {0, 0, 0}, {1, 1, 1}, [](int x, int, int) {
                                   return x;
                               }).bytes());
    auto m = make_medium(dir / "r.vol");
    CountingSampler s(3);
    EXPECT_EQ(m->transmittance(make_ray({-1, 2, 0.5}, {1, 0, 0}), kInf, s).r, 1.f);    // misses
    EXPECT_EQ(m->transmittance(make_ray({-1, 0.5, 0.5}, {1, 0, 0}), 0.9, s).r, 1.f);   // short
    EXPECT_EQ(m->transmittance(make_ray({2, 0.5, 0.5}, {1, 0, 0}), kInf, s).r, 1.f);   // past
    EXPECT_EQ(m->transmittance(make_ray({0.5, 0.5, 0.5}, {1, 0, 0}), 0.0, s).r, 1.f);  // d = 0
    EXPECT_EQ(m->transmittance(make_ray({-1, 0.5, 2}, {1, 0, 0}), kInf, s).r, 1.f);    // parallel
    EXPECT_EQ(s.draws, 0u);
    fs::remove_all(dir);
}

/// Ratio tracking where the density along the ray is constant but the grid is not: the
/// tracker is really used (min density 0).
TEST(Heterogeneous, RatioTrackingOfAConstantRegion) {
    const auto dir = femto::test::temp_dir("het-region");
    // Density 1 everywhere except the points (0, 2, 4) at (0, 2, 3), density 0, and (3, 2, 4)
    // at (1, 2, 3), density `corner` (1: the ray runs at the majorant; 4: below it), whose cells
    // the ray (y = 0.5, z = 1) does not touch.
    for (double corner : {1.0, 4.0}) {
        write_bytes(dir / "g.vol",
                    make_grid(4, 3, 5, {0, 0, 0}, {1, 2, 3}, [&](int x, int y, int z) {
                        if (y == 2 && z == 4 && x == 0) return 0.0;
                        return (x == 3 && y == 2 && z == 4) ? corner : 1.0;
                    }).bytes());
        auto m = make_medium(dir / "g.vol", 1.2);
        const Ray ray = make_ray({-1, 0.5, 1}, {1, 0, 0});
        const int n = 200000;
        const Estimate e = estimate(*m, ray, kInf, n, corner == 1 ? 11 : 12);
        const double expected = std::exp(-1.2);
        EXPECT_NEAR(e.mean, expected, 4 * e.se) << "corner " << corner << " se " << e.se;
        EXPECT_GT(e.draws, 0u);
        if (corner == 1.0) {
            // At the majorant, every tentative collision is real: estimates are 0 or 1.
            EXPECT_EQ(e.min, 0.0);
            EXPECT_EQ(e.max, 1.0);
        } else {
            EXPECT_LT(e.min, e.max);
        }
    }
    fs::remove_all(dir);
}

/// density(x) = 0.5 + 1.5 x over the box [0, 2] x [0, 1] x [0, 1] (9 x 2 x 2 points; the
/// trilinear interpolation of a linear function is that function).
double ramp(double x) { return 0.5 + 1.5 * x; }
double ramp_integral(double x0, double x1) { return 0.5 * (x1 - x0) + 0.75 * (x1 * x1 - x0 * x0); }

TEST(Heterogeneous, LinearRampMatchesTheAnalyticOpticalDepth) {
    const auto dir = femto::test::temp_dir("het-ramp");
    write_bytes(dir / "ramp.vol", make_grid(9, 2, 2, {0, 0, 0}, {2, 1, 1}, [](int x, int, int) {
                                      return ramp(2.0 * x / 8);
                                  }).bytes());
    const double scale = 0.5;
    auto m = make_medium(dir / "ramp.vol", scale);
    EXPECT_FLOAT_EQ(m->majorant(), float(scale * ramp(2.0)));

    const Vec3 v(1, 0.2, 0.1);     // from (-1, 0.2, 0.3): enters at x = 0, leaves at x = 2
    const double per_x = norm(v);  // path length per unit of x
    struct Case {
        const char* name;
        Ray ray;
        double distance, optical_depth;
    };
    const Case cases[] = {
        {"oblique_through", make_ray({-1, 0.2, 0.3}, v), kInf, scale * per_x * ramp_integral(0, 2)},
        {"oblique_ends_at_x1", make_ray({-1, 0.2, 0.3}, v), 2 * per_x,
         scale * per_x * ramp_integral(0, 1)},
        {"backwards_through", make_ray({3, 0.5, 0.5}, {-1, 0, 0}), kInf,
         scale * ramp_integral(0, 2)},
        {"starts_inside", make_ray({1, 0.5, 0.5}, {1, 0, 0}), kInf, scale * ramp_integral(1, 2)},
        {"across_y", make_ray({1.5, -1, 0.5}, {0, 1, 0}), kInf, scale * ramp(1.5)},
    };
    int seed = 100;
    for (const Case& c : cases) {
        const Estimate e = estimate(*m, c.ray, c.distance, 200000, ++seed);
        const double expected = std::exp(-c.optical_depth);
        EXPECT_NEAR(e.mean, expected, 4 * e.se) << c.name << " se " << e.se;
        EXPECT_GT(e.se, 0.0) << c.name;
        EXPECT_LT(e.se, 0.01 * expected) << c.name;  // enough samples to mean something
    }
    fs::remove_all(dir);
}

TEST(Heterogeneous, ToWorldPlacesTheBox) {
    const auto dir = femto::test::temp_dir("het-toworld");
    write_bytes(dir / "ramp.vol", make_grid(9, 2, 2, {0, 0, 0}, {2, 1, 1}, [](int x, int, int) {
                                      return ramp(2.0 * x / 8);
                                  }).bytes());
    Properties props = medium_props(dir / "ramp.vol");
    props.set_float("scale", 0.25);
    // World x = 10 + 2 x_grid: the box spans x in [10, 14], y, z in [0, 1].
    props.set_transform(
        "to_world", femto::Transform::translate({10, 0, 0}) * femto::Transform::scale({2, 1, 1}));
    auto m = make_medium(props);
    EXPECT_NEAR(m->sigma_t({12, 0.5, 0.5}).r, 0.25 * ramp(1.0), 1e-6);
    EXPECT_EQ(m->sigma_t({1, 0.5, 0.5}).r, 0.f);
    // Densities are per world unit: through the box the optical depth is
    // 0.25 * integral over x_world in [10, 14] of ramp((x - 10) / 2) = 0.25 * 2 * integral.
    const Estimate e = estimate(*m, make_ray({9, 0.5, 0.5}, {1, 0, 0}), kInf, 200000, 77);
    const double expected = std::exp(-0.25 * 2 * ramp_integral(0, 2));
    EXPECT_NEAR(e.mean, expected, 4 * e.se) << "se " << e.se;
    fs::remove_all(dir);
}

TEST(Heterogeneous, ThickMediumStaysUnbiased) {
    // Optical depth 6 through a ramp (transmittance 0.0025): most estimates fall below the
    // roulette threshold on the way; the mean must stay exp(-6).
    const auto dir = femto::test::temp_dir("het-thick");
    write_bytes(dir / "ramp.vol", make_grid(9, 2, 2, {0, 0, 0}, {2, 1, 1}, [](int x, int, int) {
                                      return ramp(2.0 * x / 8);
                                  }).bytes());
    const double depth = 6.0;
    auto m = make_medium(dir / "ramp.vol", depth / ramp_integral(0, 2));
    const int n = 400000;
    const Estimate e = estimate(*m, make_ray({-1, 0.5, 0.5}, {1, 0, 0}), kInf, n, 5);
    EXPECT_NEAR(e.mean, std::exp(-depth), 4 * e.se) << "se " << e.se;
    EXPECT_LT(e.se, 0.02 * std::exp(-depth));
    // Without roulette a walk would take residual majorant * length = 9 tentative collisions
    // on average; roulette ends most walks early (its own draws included).
    EXPECT_LT(double(e.draws) / n, 9.0);
    fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Bad input

/// Builds the medium and returns the SceneError's message ("" and a test failure if none).
std::string medium_error(const Properties& props) {
    try {
        femto::create_object(PluginKind::Medium, "heterogeneous", props);
    } catch (const femto::SceneError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected a SceneError";
    return {};
}

TEST(Heterogeneous, MalformedFilesAreSceneErrorsNamingTheFile) {
    const auto dir = femto::test::temp_dir("het-bad");
    const VolFile good =
        make_grid(2, 3, 4, {0, 0, 0}, {1, 1, 1}, [](int x, int y, int z) { return x + y + z; });
    struct Bad {
        std::string name, expect;
        std::string bytes;
    };
    std::vector<Bad> bad;
    auto with = [&](auto change) {
        VolFile v = good;
        change(v);
        return v.bytes();
    };
    bad.push_back({"empty.vol", "not a Mitsuba grid volume", ""});
    bad.push_back({"text.vol", "not a Mitsuba grid volume", "hello world, not a volume at all"});
    bad.push_back(
        {"magic.vol", "not a Mitsuba grid volume", with([](VolFile& v) { v.magic = "VOX"; })});
    bad.push_back({"version.vol", "version 2", with([](VolFile& v) { v.version = 2; })});
    bad.push_back(
        {"float16.vol", "encoding 2 (float16)", with([](VolFile& v) { v.encoding = 2; })});
    bad.push_back({"encoding.vol", "encoding 77", with([](VolFile& v) { v.encoding = 77; })});
    bad.push_back({"header.vol", "truncated header", good.bytes().substr(0, 20)});
    bad.push_back({"channels.vol", "needs", with([](VolFile& v) { v.channels = 3; })});
    bad.push_back({"six_channels.vol", "6 channels", with([](VolFile& v) { v.channels = 6; })});
    bad.push_back({"zero_channels.vol", "0 channels", with([](VolFile& v) { v.channels = 0; })});
    bad.push_back({"zero_res.vol", "invalid resolution", with([](VolFile& v) { v.res[1] = 0; })});
    bad.push_back(
        {"negative_res.vol", "invalid resolution", with([](VolFile& v) { v.res[2] = -4; })});
    bad.push_back({"huge.vol", "more than 2^31 values",
                   with([](VolFile& v) { v.res[0] = v.res[1] = v.res[2] = 1 << 20; })});
    bad.push_back({"huge2.vol", "more than 2^31 values", with([](VolFile& v) {
                       v.res[0] = v.res[1] = 2147483647;
                       v.res[2] = 2;
                   })});
    bad.push_back({"truncated.vol", "truncated", good.bytes().substr(0, good.bytes().size() - 4)});
    bad.push_back({"trailing.vol", "trailing data", good.bytes() + "xxxx"});
    bad.push_back({"wrong_size.vol", "needs", with([](VolFile& v) { v.res[0] = 3; })});
    bad.push_back({"nan.vol", "value nan at voxel (x 1, y 2, z 3)", with([](VolFile& v) {
                       v.data.back() = std::numeric_limits<float>::quiet_NaN();
                   })});
    bad.push_back({"inf.vol", "value inf",
                   with([](VolFile& v) { v.data[5] = std::numeric_limits<float>::infinity(); })});
    bad.push_back({"negative.vol", "value -0.5 at voxel (x 1, y 0, z 0)",
                   with([](VolFile& v) { v.data[1] = -0.5f; })});
    bad.push_back(
        {"flat_box.vol", "invalid bounding box", with([](VolFile& v) { v.bbox[4] = v.bbox[1]; })});
    bad.push_back({"nan_box.vol", "invalid bounding box",
                   with([](VolFile& v) { v.bbox[0] = std::numeric_limits<float>::quiet_NaN(); })});
    for (const Bad& b : bad) {
        write_bytes(dir / b.name, b.bytes);
        const std::string what = medium_error(medium_props(dir / b.name));
        EXPECT_NE(what.find((dir / b.name).string()), std::string::npos) << b.name << ": " << what;
        EXPECT_NE(what.find(b.expect), std::string::npos) << b.name << ": " << what;
        EXPECT_NE(what.find("media.xml:3:4"), std::string::npos) << b.name << ": " << what;
    }

    const std::string missing = medium_error(medium_props(dir / "missing.vol"));
    EXPECT_NE(missing.find((dir / "missing.vol").string()), std::string::npos) << missing;
    EXPECT_NE(missing.find("no such file"), std::string::npos) << missing;
    fs::create_directory(dir / "folder.vol");
    const std::string folder = medium_error(medium_props(dir / "folder.vol"));
    EXPECT_NE(folder.find("is a directory"), std::string::npos) << folder;

    // A FIFO would block a reader forever: it is refused before being opened.
    ASSERT_EQ(::mkfifo((dir / "fifo.vol").c_str(), 0600), 0);
    const std::string fifo = medium_error(medium_props(dir / "fifo.vol"));
    EXPECT_NE(fifo.find("is not a regular file"), std::string::npos) << fifo;

    // The good grid loads (so the cases above fail for their own reason).
    write_bytes(dir / "good.vol", good.bytes());
    EXPECT_NO_THROW(make_medium(dir / "good.vol"));
    fs::remove_all(dir);
}

TEST(Heterogeneous, BadParametersAreLocatedSceneErrors) {
    const auto dir = femto::test::temp_dir("het-params");
    write_bytes(dir / "g.vol", make_grid(2, 2, 2, {0, 0, 0}, {1, 1, 1}, [](int, int, int) {
                                   return 1.0;
                               }).bytes());
    const femto::SourceLocation loc{"media.xml", 9, 7};
    {
        Properties p = medium_props(dir / "g.vol");
        p.set("scale", Properties::Type::Float, -1.0, loc);
        const std::string what = medium_error(p);
        EXPECT_NE(what.find("media.xml:9:7"), std::string::npos) << what;
        EXPECT_NE(what.find("scale"), std::string::npos) << what;
    }
    {
        Properties p = medium_props(dir / "g.vol");
        p.set("albedo", Properties::Type::Color, Color(0.5f, 1.5f, 0.5f), loc);
        const std::string what = medium_error(p);
        EXPECT_NE(what.find("media.xml:9:7"), std::string::npos) << what;
        EXPECT_NE(what.find("albedo"), std::string::npos) << what;
    }
    {
        Properties p = medium_props(dir / "g.vol");
        p.set("eta", Properties::Type::Float, 0.5, loc);
        EXPECT_NE(medium_error(p).find("media.xml:9:7"), std::string::npos);
    }
    {
        Properties p = medium_props(dir / "g.vol");
        p.set("scale", Properties::Type::Float, 1e39, loc);  // scale * density overflows
        EXPECT_NE(medium_error(p).find("overflows"), std::string::npos);
    }
    {
        // No density: Mitsuba 3's default, sigma_t 1 everywhere.
        Properties p("heterogeneous", {"media.xml", 2, 1});
        EXPECT_FLOAT_EQ(make_medium(p)->sigma_t({5, 5, 5}).r, 1.f);
    }
    {
        Properties p = medium_props(dir / "g.vol");
        p.set_float("sigma_t", 3.0);  // Mitsuba 3's name for the density: one or the other
        EXPECT_NE(medium_error(p).find("not both"), std::string::npos);
    }
    {
        // A 3-channel grid is a colour (an albedo), not a density.
        VolFile rgb = make_grid(2, 2, 2, {0, 0, 0}, {1, 1, 1}, [](int, int, int) { return 1.0; });
        rgb.channels = 3;
        rgb.data.resize(rgb.data.size() * 3, 0.5f);
        write_bytes(dir / "rgb.vol", rgb.bytes());
        const std::string what = medium_error(medium_props(dir / "rgb.vol"));
        EXPECT_NE(what.find("\"density\" has 3 channels"), std::string::npos) << what;
        EXPECT_NE(what.find("media.xml:3:4"), std::string::npos) << what;
    }
    fs::remove_all(dir);
}

// Ratio tracking takes ~ majorant x chord steps per ray: a grid that would need more than
// 1e4 is refused (a voxel of 1e6 made a second-long render take minutes, 1e10 never ended).
TEST(Heterogeneous, GridsTooDenseToTrackAreRefused) {
    const auto dir = femto::test::temp_dir("het-dense");
    auto one_dense_voxel = [&](double density) {
        const fs::path file = dir / ("d" + std::to_string(int(std::log10(density))) + ".vol");
        write_bytes(file, make_grid(2, 2, 2, {0, 0, 0}, {1, 1, 1}, [=](int x, int y, int z) {
                              return x + y + z == 0 ? density : 0.0;
                          }).bytes());
        return file;
    };
    for (const double density : {1e6, 1e10}) {
        const std::string what = medium_error(medium_props(one_dense_voxel(density)));
        EXPECT_NE(what.find("times the longest chord through its box (1.73205 scene units)"),
                  std::string::npos)
            << what;
        EXPECT_NE(what.find("femto accepts at most 10000"), std::string::npos) << what;
    }
    // The chord is measured in the scene: scaling the box down makes the same grid trackable.
    Properties p = medium_props(one_dense_voxel(1e6));
    femto::Transform::Matrix small{};
    for (int i = 0; i < 3; ++i) small[i][i] = 1e-3;
    small[3][3] = 1;
    p.set("to_world", Properties::Type::Transform, femto::Transform(small));
    EXPECT_NO_THROW(femto::create_object(PluginKind::Medium, "heterogeneous", p));
    // A constant grid needs no tracking (its transmittance is exact), however dense.
    write_bytes(dir / "c.vol", make_grid(2, 2, 2, {0, 0, 0}, {1, 1, 1}, [](int, int, int) {
                                   return 1e6;
                               }).bytes());
    EXPECT_NO_THROW(
        femto::create_object(PluginKind::Medium, "heterogeneous", medium_props(dir / "c.vol")));
    fs::remove_all(dir);
}

// Programmatic Properties are not resolved by anyone: the plugin opens the name it is given
// (the loader resolves names written in scene files; test_volumes.cpp tests that).
TEST(Heterogeneous, NamesGivenDirectlyAreOpenedAsGiven) {
    const auto dir = femto::test::temp_dir("het-direct");
    write_bytes(dir / "g.vol", make_grid(2, 2, 2, {0, 0, 0}, {1, 1, 1}, [](int, int, int) {
                                   return 3.0;
                               }).bytes());
    EXPECT_FLOAT_EQ(make_medium(dir / "g.vol")->majorant(), 3.f);
    Properties p("heterogeneous", {(dir / "scene.xml").string(), 2, 1});
    p.set("density", Properties::Type::String, std::string("g.vol"),
          {(dir / "scene.xml").string(), 3, 5});
    const std::string what = medium_error(p);
    EXPECT_NE(what.find("scene.xml:3:5"), std::string::npos) << what;
    EXPECT_NE(what.find("no such file"), std::string::npos) << what;
    fs::remove_all(dir);
}

}  // namespace

namespace {

TEST(Heterogeneous, LoadsFromASceneFileWithARelativeDensityPath) {
    const auto dir = femto::test::temp_dir("het-scene");
    write_bytes(dir / "smoke.vol", make_grid(2, 2, 2, {-1, -1, -1}, {1, 1, 1}, [](int, int, int) {
                                       return 2.0;
                                   }).bytes());
    const std::string medium =
        "<shape type=\"cube\"><bsdf type=\"null\"/>\n"
        "  <medium name=\"interior\" type=\"heterogeneous\">\n"
        "    <string name=\"density\" value=\"DENSITY\"/>\n"
        "    <float name=\"scale\" value=\"0.5\"/>\n"
        "    <phase type=\"hg\"><float name=\"g\" value=\"0.6\"/></phase>\n"
        "  </medium>\n"
        "</shape>";
    auto scene_with = [&](const std::string& density) {
        std::string body = medium;
        body.replace(body.find("DENSITY"), 7, density);
        return femto::test::scene_xml(body);
    };
    femto::test::write_text(dir / "scene.xml", scene_with("smoke.vol"));
    // The working directory is not the scene's folder: the name resolves next to the scene.
    std::unique_ptr<femto::Scene> scene;
    ASSERT_NO_THROW(scene = femto::load_scene((dir / "scene.xml").string()));
    ASSERT_EQ(scene->shapes().size(), 1u);
    const Medium* m = scene->shapes()[0]->interior();
    ASSERT_TRUE(m);
    EXPECT_EQ(m->type_name(), "heterogeneous");
    EXPECT_FLOAT_EQ(m->majorant(), 1.f);
    EXPECT_EQ(m->phase().type_name(), "hg");

    femto::test::write_text(dir / "bad.xml", scene_with("nothing-here.vol"));
    try {
        femto::load_scene((dir / "bad.xml").string());
        ADD_FAILURE() << "a missing density file was accepted";
    } catch (const femto::SceneError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("bad.xml:"), std::string::npos) << what;  // located in the scene
        EXPECT_NE(what.find("nothing-here.vol"), std::string::npos) << what;
    }
    fs::remove_all(dir);
}

}  // namespace
