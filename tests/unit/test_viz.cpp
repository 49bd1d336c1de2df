// `femto viz` computations (femto/viz.h) and the streak film (thesis ch. 4.3-4.6). Built into
// femto_io_tests (linked with libfemto_io), not into femto_unit_tests.
//
// Tolerances:
//  - Synthetic cubes hold exact binary fractions; peak bins, slices and whole-bin unwarps are
//    exact. A fractional unwarp shift interpolates linearly in float: energy is conserved to
//    float rounding of the sums (relative 1e-5).
//  - The streak film and the transient film receive the same camera samples (the samplers are
//    deterministic per pixel and sample index) and add them in the same order (the renderer
//    merges tiles in a fixed 2x2 colouring), so their rows agree to float rounding: 1e-6
//    relative, plus 1e-12 absolute for empty bins. Their depths are sums of the same terms in
//    the same order (1e-6 too). Unwarping both with the same depth interpolates the same two
//    bins with the same weights: 2e-6 (the inputs' 1e-6 plus the rounding of each side).
//  - PNG previews of equal images may differ by one 8-bit step (float rounding at a step).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "femto/film.h"
#include "femto/host.h"
#include "femto/image_io.h"
#include "femto/memory.h"
#include "femto/sensor.h"
#include "femto/tfilter.h"
#include "femto/viz.h"
#include "scene_util.h"
#include "util/memory_limit.h"

using namespace femto;

namespace {

std::string fmt_double(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

io::Cube make_cube(int W, int H, int T, double start, double bw, const char* time = "camera") {
    io::Cube c;
    c.width = W;
    c.height = H;
    c.bins = T;
    c.data.assign(size_t(W) * size_t(H) * size_t(T) * 3, 0.f);
    c.attributes = {{"femto:start", fmt_double(start)},
                    {"femto:bin_width", fmt_double(bw)},
                    {"femto:bins", std::to_string(T)},
                    {"femto:time", time}};
    return c;
}

float& at(io::Cube& c, int x, int y, int t, int ch) {
    return c.data[((size_t(y) * size_t(c.width) + size_t(x)) * size_t(c.bins) + size_t(t)) * 3 +
                  size_t(ch)];
}

double pixel_energy(const io::Cube& c, int x, int y) {
    double e = 0;
    for (int t = 0; t < c.bins; ++t)
        for (int ch = 0; ch < 3; ++ch)
            e += c.data[((size_t(y) * size_t(c.width) + size_t(x)) * size_t(c.bins) + size_t(t)) *
                            3 +
                        size_t(ch)];
    return e;
}

}  // namespace

// ---- peak time ------------------------------------------------------------------------------

TEST(Viz, PeakTimeOfSyntheticCube) {
    const int W = 5, H = 3, T = 12;
    io::Cube c = make_cube(W, H, T, 2.0, 0.5);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            if (x == 4 && y == 2) continue;  // a black pixel
            const int peak = (2 * x + 3 * y) % T;
            for (int t = 0; t < T; ++t)
                for (int ch = 0; ch < 3; ++ch) at(c, x, y, t, ch) = 0.125f;
            at(c, x, y, peak, 1) = 4.f;            // green peak: the luminance maximum
            at(c, x, y, (peak + 5) % T, 0) = 2.f;  // a red bump with less luminance
        }
    const TimeGrid grid = viz::time_grid(c);
    ASSERT_TRUE(grid.known);
    EXPECT_EQ(grid.frame, TimeFrame::Camera);
    EXPECT_EQ(grid.bins, T);
    const std::vector<int> bins = viz::peak_bins(c);
    const std::vector<float> times = viz::peak_times(c, grid);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t p = size_t(y) * W + size_t(x);
            if (x == 4 && y == 2) {
                EXPECT_EQ(bins[p], -1);
                EXPECT_TRUE(std::isnan(times[p]));
                continue;
            }
            const int peak = (2 * x + 3 * y) % T;
            EXPECT_EQ(bins[p], peak) << x << "," << y;
            EXPECT_FLOAT_EQ(times[p], float(2.0 + (peak + 0.5) * 0.5));
        }
    // The picture: black where the pixel is black, coloured elsewhere; the earliest peak is
    // red, the latest blue.
    const std::vector<float> img = viz::peak_time_image(c);
    const size_t black = (size_t(2) * W + 4) * 3;
    EXPECT_EQ(img[black] + img[black + 1] + img[black + 2], 0.f);
    const size_t first = 0;                       // (0, 0): peak bin 0, the earliest
    const size_t last = (size_t(1) * W + 3) * 3;  // (3, 1): peak bin 9
    EXPECT_GT(img[first], 0.f);
    EXPECT_EQ(img[first + 2], 0.f);
    EXPECT_GT(img[last + 2], img[last]);
    // Time override for a cube without attributes (a .npy): --start / --bin-width.
    io::Cube bare = c;
    bare.attributes.clear();
    EXPECT_FALSE(viz::time_grid(bare).known);
    EXPECT_EQ(viz::time_grid(bare).frame, TimeFrame::Unknown);
    const TimeGrid given = viz::time_grid(bare, 1.0, 0.25);
    EXPECT_TRUE(given.known);
    EXPECT_DOUBLE_EQ(given.bin_centre(2), 1.625);
}

// ---- unwarp (eq. 4.1) ---------------------------------------------------------------------

// A camera-time cube whose pixel (x, y) is lit from bin `first` on, with depth z(x, y).
io::Cube warped_cube(double bw, int first, const std::vector<float>& depth, int W, int H, int T) {
    io::Cube c = make_cube(W, H, T, 3.0, bw);
    c.depth = depth;
    uint32_t state = 12345;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int t = first; t < T; ++t)
                for (int ch = 0; ch < 3; ++ch) {
                    state = state * 1664525u + 1013904223u;
                    at(c, x, y, t, ch) = float(state >> 8) / float(1 << 24);
                }
    return c;
}

double start_of(const io::Cube& c) { return std::stod(*c.attribute("femto:start")); }

TEST(Viz, UnwarpWholeBinsRoundTripIsExact) {
    const int W = 4, H = 2, T = 16;
    const double bw = 0.25;
    std::vector<float> depth(W * H);
    for (int p = 0; p < W * H; ++p) depth[size_t(p)] = 0.5f * float(p % W + 1);  // 2..8 bins
    depth[5] = -1.f;  // nothing hit: not shifted
    const io::Cube cam = warped_cube(bw, 6, depth, W, H, T);
    const viz::UnwarpResult world = viz::unwarp(cam, viz::time_grid(cam), true);
    EXPECT_EQ(*world.cube.attribute("femto:time"), "world");
    EXPECT_EQ(world.dropped, 0.0);
    EXPECT_EQ(world.cube.depth, cam.depth);
    const double ws = start_of(world.cube);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t p = size_t(y) * W + size_t(x);
            const double z = depth[p] > 0 ? depth[p] : 0.0;
            EXPECT_EQ(pixel_energy(world.cube, x, y), pixel_energy(cam, x, y));
            // t_world = t_camera - z: world bin j holds camera bin i with the same time - z.
            for (int j = 0; j < world.cube.bins; ++j) {
                const double t = ws + j * bw;
                const long i = std::lround((t + z - 3.0) / bw);
                for (int ch = 0; ch < 3; ++ch) {
                    const float expect =
                        i >= 0 && i < T ? cam.data[((p * T) + size_t(i)) * 3 + size_t(ch)] : 0.f;
                    ASSERT_EQ(
                        world.cube.data[(p * size_t(world.cube.bins) + size_t(j)) * 3 + size_t(ch)],
                        expect)
                        << x << "," << y << " bin " << j;
                }
            }
        }
    // Back to camera time: the same series at the same times.
    EXPECT_THROW(viz::unwarp(world.cube, viz::time_grid(world.cube), true), SceneError);
    const viz::UnwarpResult back = viz::unwarp(world.cube, viz::time_grid(world.cube), false);
    EXPECT_EQ(*back.cube.attribute("femto:time"), "camera");
    const double bs = start_of(back.cube);
    for (size_t p = 0; p < size_t(W * H); ++p)
        for (int j = 0; j < back.cube.bins; ++j) {
            const long i = std::lround((bs + j * bw - 3.0) / bw);
            for (int ch = 0; ch < 3; ++ch) {
                const float expect =
                    i >= 0 && i < T ? cam.data[(p * T + size_t(i)) * 3 + size_t(ch)] : 0.f;
                ASSERT_EQ(back.cube.data[(p * size_t(back.cube.bins) + size_t(j)) * 3 + size_t(ch)],
                          expect);
            }
        }
    // Every original non-zero bin is inside the round-tripped window.
    EXPECT_LE(bs, 3.0 + 6 * bw + 1e-12);
    EXPECT_GE(bs + back.cube.bins * bw, 3.0 + T * bw - 1e-12);
}

TEST(Viz, UnwarpKeepWindowRoundTrip) {
    // Energy in the middle of the window, shifts of up to 3 bins: nothing leaves the window.
    const int W = 3, H = 1, T = 20;
    const double bw = 0.5;
    const std::vector<float> depth = {0.5f, 1.0f, 1.5f};
    io::Cube cam = warped_cube(bw, 0, depth, W, H, T);
    for (size_t p = 0; p < 3; ++p)
        for (int t = 0; t < T; ++t)
            if (t < 6 || t > 13)
                for (int ch = 0; ch < 3; ++ch) cam.data[(p * T + size_t(t)) * 3 + size_t(ch)] = 0;
    const viz::UnwarpResult world = viz::unwarp(cam, viz::time_grid(cam), true, true);
    EXPECT_EQ(world.cube.bins, T);
    EXPECT_EQ(start_of(world.cube), 3.0);
    EXPECT_EQ(world.dropped, 0.0);
    const viz::UnwarpResult back = viz::unwarp(world.cube, viz::time_grid(world.cube), false, true);
    EXPECT_EQ(back.cube.data, cam.data);
    // Depth 1.5 shifts 3 bins: energy at the start of the window falls out and is reported.
    io::Cube early = warped_cube(bw, 0, depth, W, H, T);
    const viz::UnwarpResult cut = viz::unwarp(early, viz::time_grid(early), true, true);
    EXPECT_GT(cut.dropped, 0.0);
    EXPECT_LT(cut.dropped, 0.2);
}

TEST(Viz, UnwarpFractionalShiftConservesEnergyAndMovesMeanTime) {
    const int W = 3, H = 2, T = 24;
    const double bw = 0.1;
    const std::vector<float> depth = {0.33f, 0.47f, 1.05f, 0.01f, 2.2f, 0.5f};
    const io::Cube cam = warped_cube(bw, 3, depth, W, H, T);
    auto mean_time = [](const io::Cube& c, size_t p, double start, double bw) {
        double e = 0, et = 0;
        for (int t = 0; t < c.bins; ++t) {
            double v = 0;
            for (int ch = 0; ch < 3; ++ch)
                v += c.data[(p * size_t(c.bins) + size_t(t)) * 3 + size_t(ch)];
            e += v;
            et += v * (start + (t + 0.5) * bw);
        }
        return et / e;
    };
    const viz::UnwarpResult world = viz::unwarp(cam, viz::time_grid(cam), true);
    const viz::UnwarpResult back = viz::unwarp(world.cube, viz::time_grid(world.cube), false);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t p = size_t(y) * W + size_t(x);
            const double e = pixel_energy(cam, x, y);
            EXPECT_NEAR(pixel_energy(world.cube, x, y), e, 1e-5 * e);
            EXPECT_NEAR(pixel_energy(back.cube, x, y), e, 1e-5 * e);
            // Box resampling of a shifted piecewise-constant series moves its mean exactly.
            EXPECT_NEAR(mean_time(world.cube, p, start_of(world.cube), bw),
                        mean_time(cam, p, 3.0, bw) - depth[p], 1e-5);
            EXPECT_NEAR(mean_time(back.cube, p, start_of(back.cube), bw),
                        mean_time(cam, p, 3.0, bw), 1e-5);
        }
}

// A wide streak image whose depths spread its pixels over more bins than memory holds: a
// message (exit 2), not an allocation failure or the OOM killer.
TEST(Viz, UnwarpRefusesACubeLargerThanMemory) {
    const double ram = usable_memory_bytes();
    const int W = 1 << 17;
    const double bins_needed = 0.9 * ram / (double(W) * 3 * sizeof(float));
    if (!(ram > 0) || bins_needed > double(1 << 20) ||
        0.9 * ram > double(int64_t(1) << 36))  // the fixed limits refuse it first
        GTEST_SKIP() << "this machine's memory is beyond the fixed limits";
    io::Cube c = make_cube(W, 1, 2, 0.0, 1.0);
    c.depth.assign(size_t(W), 0.f);
    c.depth[1] = float(bins_needed);  // a shift of that many bins (bin width 1)
    try {
        viz::unwarp(c, viz::time_grid(c), true);
        FAIL() << "no error";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("GiB, more than 3/4 of this"), std::string::npos)
            << e.what();
    }
}

// A container's limit is what the OOM killer enforces, so the memory rule reads it: "max" (v2)
// sets none, a count is bytes, v1's "no limit" is a huge count the physical memory undercuts.
TEST(Memory, ReadsAControlGroupsLimit) {
    EXPECT_FALSE(detail::parse_cgroup_limit("max\n"));
    EXPECT_FALSE(detail::parse_cgroup_limit(""));
    EXPECT_FALSE(detail::parse_cgroup_limit("-1\n"));
    EXPECT_FALSE(detail::parse_cgroup_limit("12abc\n"));
    EXPECT_FALSE(detail::parse_cgroup_limit("0\n"));
    EXPECT_EQ(detail::parse_cgroup_limit("2147483648\n"), 2147483648.0);
    EXPECT_EQ(detail::parse_cgroup_limit("9223372036854771712\n"), 9223372036854771712.0);
    // The process's group and its ancestors, the smallest limit winning: v1 (memory
    // controller) and v2 (unified) trees built in a temporary folder.
    const auto root = test::temp_dir("cgroup-tree");
    const auto put = [&](const std::string& file, const std::string& text) {
        std::filesystem::create_directories((root / file).parent_path());
        std::ofstream(root / file) << text;
    };
    put("memory/memory.limit_in_bytes", "9223372036854771712\n");
    put("memory/a/memory.limit_in_bytes", "500\n");
    put("memory/a/b/memory.limit_in_bytes", "1000\n");
    EXPECT_EQ(detail::cgroup_memory_limit("4:memory:/a/b\n3:cpu:/x\n", root.string()), 500.0);
    EXPECT_EQ(detail::cgroup_memory_limit("4:cpuacct,memory:/a\n", root.string()), 500.0);
    EXPECT_FALSE(detail::cgroup_memory_limit("0::/a/b\n", root.string()));  // not unified
    put("cgroup.controllers", "memory\n");
    put("x/memory.max", "2000\n");
    put("x/y/memory.max", "max\n");
    EXPECT_EQ(detail::cgroup_memory_limit("0::/x/y\n", root.string()), 2000.0);
    EXPECT_FALSE(detail::cgroup_memory_limit("0::/\n", root.string()));
    EXPECT_FALSE(detail::cgroup_memory_limit("garbage", root.string()));

    const double ram = physical_memory_bytes(), usable = usable_memory_bytes();
    if (ram > 0) {
        EXPECT_GT(usable, 0.0);
        EXPECT_LE(usable, ram);
    }
}

TEST(Viz, UnwarpNeedsDepthAndTimeFrame) {
    io::Cube c = make_cube(2, 2, 4, 0.0, 1.0);
    at(c, 0, 0, 1, 0) = 1.f;
    EXPECT_THROW(viz::unwarp(c, viz::time_grid(c), true), SceneError);  // no depth
    c.depth.assign(4, 1.f);
    EXPECT_NO_THROW(viz::unwarp(c, viz::time_grid(c), true));
    EXPECT_THROW(viz::unwarp(c, viz::time_grid(c), false), SceneError);  // already camera
    io::Cube unknown = c;
    unknown.attributes = {{"femto:start", "0"}, {"femto:bin_width", "1"}};
    EXPECT_THROW(viz::unwarp(unknown, viz::time_grid(unknown), true), SceneError);
    unknown.attributes.clear();
    EXPECT_THROW(viz::unwarp(unknown, viz::time_grid(unknown), true), SceneError);  // no axis
}

// ---- streak images (the x-t image of one row, a cube of height 1) -----------------------------

TEST(Viz, StreakImageFileRoundTrip) {
    const auto dir = test::temp_dir("viz-streak-file");
    io::Cube c = make_cube(5, 3, 4, 1.5, 0.25);
    for (size_t i = 0; i < c.data.size(); ++i) c.data[i] = float(i) * 0.5f;
    c.depth = {1, 2, 3, 4, 5, 6, 7, -1, 9, 10, 11, 12, 13, 14, 15};
    io::Attributes attrs = c.attributes;
    attrs.push_back({"femto:row", "1"});
    const std::string path = (dir / "s.exr").string();
    viz::write_streak_exr(path, c, 1, attrs);
    EXPECT_THROW(viz::write_streak_exr((dir / "x.exr").string(), c, 3, attrs), SceneError);
    // The image as any reader sees it: RGB, width x bins, time downward.
    int w = 0, h = 0;
    const std::vector<float> rgb = io::read_image_rgb(path, w, h, false);
    EXPECT_EQ(w, 5);
    EXPECT_EQ(h, 4);
    EXPECT_EQ(rgb, viz::streak_slice(c, 1));
    // femto viz reads it as a cube of height 1 with the row's depth (channel Z).
    const io::Cube s = viz::load_cube(path);
    ASSERT_TRUE(viz::is_streak(s));
    EXPECT_FALSE(viz::is_streak(c));
    EXPECT_EQ(s.width, 5);
    EXPECT_EQ(s.height, 1);
    EXPECT_EQ(s.bins, 4);
    EXPECT_EQ(s.data, std::vector<float>(c.data.begin() + 5 * 4 * 3, c.data.begin() + 10 * 4 * 3));
    EXPECT_EQ(s.depth, std::vector<float>({6, 7, -1, 9, 10}));
    EXPECT_EQ(*s.attribute("femto:row"), "1");
    EXPECT_DOUBLE_EQ(viz::time_grid(s).start, 1.5);
    EXPECT_EQ(viz::time_grid(s).frame, TimeFrame::Camera);
    // Without depth there is no channel Z, and unwarping says what is missing.
    io::Cube flat = c;
    flat.depth.clear();
    viz::write_streak_exr(path, flat, 2, attrs);
    const io::Cube f = viz::load_cube(path);
    ASSERT_TRUE(viz::is_streak(f));
    EXPECT_TRUE(f.depth.empty());
    try {
        viz::unwarp(f, viz::time_grid(f), true);
        ADD_FAILURE();
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("streak image has no channel Z"), std::string::npos)
            << e.what();
    }
    std::filesystem::remove_all(dir);
}

// As Viz.UnwarpWholeBinsRoundTripIsExact, for a streak image through its file: camera ->
// world -> camera returns the image, and each output is again a streak image.
TEST(Viz, StreakImageUnwarpWholeBinsRoundTripIsExact) {
    const auto dir = test::temp_dir("viz-streak-unwarp");
    const int W = 6, T = 16;
    const double bw = 0.25;
    std::vector<float> depth(W);
    for (int x = 0; x < W; ++x) depth[size_t(x)] = 0.25f * float(2 * x + 1);  // 1..11 bins
    depth[3] = -1.f;  // nothing hit: not shifted
    const io::Cube cam = warped_cube(bw, 6, depth, W, 1, T);
    io::Attributes attrs = cam.attributes;
    attrs.push_back({"femto:row", "7"});
    auto through_file = [&](const io::Cube& c, const std::string& name) {
        const std::string path = (dir / name).string();
        viz::write_streak_exr(path, c, 0, c.attributes);
        io::Cube back = viz::load_cube(path);
        EXPECT_TRUE(viz::is_streak(back)) << name;
        EXPECT_EQ(back.data, c.data) << name;
        EXPECT_EQ(back.depth, c.depth) << name;
        return back;
    };
    io::Cube labelled = cam;
    labelled.attributes = attrs;
    const io::Cube in = through_file(labelled, "cam.exr");
    const io::Cube world = through_file(viz::unwarp(in, viz::time_grid(in), true).cube, "w.exr");
    EXPECT_EQ(*world.attribute("femto:time"), "world");
    EXPECT_EQ(*world.attribute("femto:row"), "7");
    EXPECT_NE(world.attribute("femto:unwarped"), nullptr);
    EXPECT_EQ(*world.attribute("femto:bins"), std::to_string(world.bins));
    const double ws = start_of(world);
    for (int x = 0; x < W; ++x) {
        const size_t p = size_t(x);
        const double z = depth[p] > 0 ? depth[p] : 0.0;
        EXPECT_EQ(pixel_energy(world, x, 0), pixel_energy(cam, x, 0));
        for (int j = 0; j < world.bins; ++j) {
            const long i = std::lround((ws + j * bw + z - 3.0) / bw);  // t_world = t_camera - z
            for (int ch = 0; ch < 3; ++ch) {
                const float expect =
                    i >= 0 && i < T ? cam.data[((p * T) + size_t(i)) * 3 + size_t(ch)] : 0.f;
                ASSERT_EQ(world.data[(p * size_t(world.bins) + size_t(j)) * 3 + size_t(ch)], expect)
                    << x << " bin " << j;
            }
        }
    }
    const io::Cube back =
        through_file(viz::unwarp(world, viz::time_grid(world), false).cube, "c.exr");
    EXPECT_EQ(*back.attribute("femto:time"), "camera");
    const double bs = start_of(back);
    for (size_t p = 0; p < size_t(W); ++p)
        for (int j = 0; j < back.bins; ++j) {
            const long i = std::lround((bs + j * bw - 3.0) / bw);
            for (int ch = 0; ch < 3; ++ch) {
                const float expect =
                    i >= 0 && i < T ? cam.data[(p * T + size_t(i)) * 3 + size_t(ch)] : 0.f;
                ASSERT_EQ(back.data[(p * size_t(back.bins) + size_t(j)) * 3 + size_t(ch)], expect);
            }
        }
    EXPECT_LE(bs, 3.0 + 6 * bw + 1e-12);
    EXPECT_GE(bs + back.bins * bw, 3.0 + T * bw - 1e-12);
    std::filesystem::remove_all(dir);
}

// ---- streak slice, frames, rainbow ----------------------------------------------------------

TEST(Viz, StreakSliceEqualsCubeRow) {
    const int W = 6, H = 4, T = 5;
    io::Cube c = make_cube(W, H, T, 0.0, 1.0);
    for (size_t i = 0; i < c.data.size(); ++i) c.data[i] = float(i) * 0.25f;
    const std::vector<float> s = viz::streak_slice(c, 2);
    ASSERT_EQ(s.size(), size_t(W * T * 3));
    for (int t = 0; t < T; ++t)
        for (int x = 0; x < W; ++x)
            for (int ch = 0; ch < 3; ++ch)
                EXPECT_EQ(s[(size_t(t) * W + size_t(x)) * 3 + size_t(ch)], at(c, x, 2, t, ch));
    EXPECT_THROW(viz::streak_slice(c, 4), SceneError);
    EXPECT_THROW(viz::streak_slice(c, -1), SceneError);
}

TEST(Viz, FramesShareOneExposure) {
    // Frame 0 is bright, frame 3 dim: with the cube's single reference level the dim frame
    // stays dim (a per-frame exposure would brighten it to the same display value).
    const int W = 8, H = 8, T = 4;
    io::Cube c = make_cube(W, H, T, 0.0, 1.0);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int ch = 0; ch < 3; ++ch) {
                at(c, x, y, 0, ch) = 1.f;
                at(c, x, y, 3, ch) = 0.01f;
            }
    const float ref = viz::reference_level(c);
    EXPECT_FLOAT_EQ(ref, 1.f);
    const size_t n = size_t(W) * H;
    for (viz::Tone tone : {viz::Tone::Linear, viz::Tone::Log}) {
        const auto f0 = viz::tone_map(viz::frame(c, 0).data(), n, ref, 0.f, tone);
        const auto f3 = viz::tone_map(viz::frame(c, 3).data(), n, ref, 0.f, tone);
        EXPECT_NEAR(f0[0], 1.f, 1e-3);
        EXPECT_LT(f3[0], 0.5f * f0[0]);
        EXPECT_GT(f3[0], 0.f);
        // The same radiance gives the same display value in every frame.
        io::Cube d = c;
        at(d, 1, 1, 3, 0) = 1.f;
        const auto g3 = viz::tone_map(viz::frame(d, 3).data(), n, ref, 0.f, tone);
        EXPECT_EQ(g3[(size_t(1) * W + 1) * 3], f0[0]);
    }
    // The log curve shows dim values brighter than the linear one.
    const auto lin = viz::tone_map(viz::frame(c, 3).data(), n, ref, 0.f, viz::Tone::Linear);
    const auto lg = viz::tone_map(viz::frame(c, 3).data(), n, ref, 0.f, viz::Tone::Log);
    EXPECT_GT(lg[0], lin[0]);
    EXPECT_THROW(viz::parse_tone("gamma"), SceneError);
}

TEST(Viz, RainbowFusionTintsByTime) {
    const int W = 3, H = 1, T = 5;
    io::Cube c = make_cube(W, H, T, 0.0, 1.0);
    for (int ch = 0; ch < 3; ++ch) {
        at(c, 0, 0, 0, ch) = 1.f;  // early: red
        at(c, 1, 0, 4, ch) = 1.f;  // late: blue
        at(c, 2, 0, 0, ch) = 1.f;  // both
        at(c, 2, 0, 4, ch) = 1.f;
    }
    const std::vector<float> r = viz::rainbow_fusion(c);
    EXPECT_FLOAT_EQ(r[0], 1.f);
    EXPECT_FLOAT_EQ(r[1], 0.f);
    EXPECT_FLOAT_EQ(r[2], 0.f);
    EXPECT_FLOAT_EQ(r[3], 0.f);
    EXPECT_FLOAT_EQ(r[4], 0.f);
    EXPECT_FLOAT_EQ(r[5], 1.f);
    EXPECT_FLOAT_EQ(r[6], 1.f);
    EXPECT_FLOAT_EQ(r[8], 1.f);
    const Color mid = viz::time_colour(0.5);
    EXPECT_FLOAT_EQ(mid.g, 1.f);
}

// ---- reference level: a lamp in view must not set it ---------------------------------------

namespace {

// A dim room seen at depth 2 (camera time; bin 8 of 0.25) with a tiny, very bright lamp: the
// lamp's pixels (x 6..8, y 0..1; 6 of 256 pixels, more than the 0.5 % above a 99.5th
// percentile) shine 500 at their own depth, the room's pixels peak at bins 12..19 with 0.5 to
// 1, and one noisy pixel peaks late, at bin 38.
constexpr int kRoomSize = 16, kRoomBins = 40;
bool is_lamp(int x, int y) { return x >= 6 && x <= 8 && y <= 1; }
int room_peak(int x, int y) { return x == 15 && y == 15 ? 38 : 12 + (x + y) % 8; }

io::Cube room_with_lamp(const char* time = "camera") {
    const int N = kRoomSize;
    io::Cube c = make_cube(N, N, kRoomBins, 0.0, 0.25, time);
    c.depth.assign(size_t(N) * N, 2.f);
    const int lamp_bin = std::string(time) == "world" ? 0 : 8;
    for (int y = 0; y < N; ++y)
        for (int x = 0; x < N; ++x)
            for (int ch = 0; ch < 3; ++ch) {
                if (is_lamp(x, y)) {
                    at(c, x, y, lamp_bin, ch) = 500.f;
                    at(c, x, y, 20, ch) = 0.01f;  // the room's light the lamp reflects
                    continue;
                }
                at(c, x, y, room_peak(x, y), ch) = 0.5f + 0.5f * float(x) / float(N - 1);
                at(c, x, y, room_peak(x, y) + 1, ch) = 0.1f;
            }
    return c;
}

float display_max(const std::vector<float>& img, int x, int y) {
    const size_t i = (size_t(y) * kRoomSize + size_t(x)) * 3;
    return std::max({img[i], img[i + 1], img[i + 2]});
}

}  // namespace

TEST(Viz, EmitterPixelsSeeLightAtTheirOwnDepth) {
    for (const char* time : {"camera", "world"}) {
        const io::Cube c = room_with_lamp(time);
        const std::vector<uint8_t> emitter = viz::emitter_pixels(c);
        ASSERT_EQ(emitter.size(), size_t(kRoomSize) * kRoomSize);
        for (int y = 0; y < kRoomSize; ++y)
            for (int x = 0; x < kRoomSize; ++x)
                EXPECT_EQ(emitter[size_t(y) * kRoomSize + size_t(x)], is_lamp(x, y) ? 1 : 0)
                    << time << " " << x << "," << y;
    }
    // Without a depth part (a .npy) or a time frame nothing can be recognised.
    io::Cube bare = room_with_lamp();
    bare.depth.clear();
    for (uint8_t e : viz::emitter_pixels(bare)) EXPECT_EQ(e, 0);
    io::Cube no_frame = room_with_lamp();
    no_frame.attributes.pop_back();  // femto:time
    for (uint8_t e : viz::emitter_pixels(no_frame)) EXPECT_EQ(e, 0);
}

TEST(Viz, LampInViewDoesNotDarkenThePictures) {
    const io::Cube c = room_with_lamp();
    // Frames: the level comes from the room (its largest value is 1), not from the lamp.
    const float frame_level = viz::reference_level(c);
    EXPECT_GE(frame_level, 0.5f);
    EXPECT_LE(frame_level, 1.f);
    // Peak time: every room pixel is at least half bright, the lamp saturates.
    const std::vector<float> peak = viz::peak_time_image(c);
    for (int y = 0; y < kRoomSize; ++y)
        for (int x = 0; x < kRoomSize; ++x)
            EXPECT_GT(display_max(peak, x, y), is_lamp(x, y) ? 0.99f : 0.5f) << x << "," << y;
    // The colours span the room's peaks, not the lamp's early one or the single late one: the
    // room's earliest peak (bin 12) is red, its latest (bin 19) blue.
    const size_t earliest = 0, latest = (size_t(15) * kRoomSize + 14) * 3;  // (0,0), (14,15)
    EXPECT_GT(peak[earliest], 0.5f);
    EXPECT_EQ(peak[earliest + 1], 0.f);
    EXPECT_EQ(peak[earliest + 2], 0.f);
    EXPECT_GT(peak[latest + 2], 0.5f);
    EXPECT_EQ(peak[latest], 0.f);
    // Rainbow fusion: the level of the fused image without the lamp; the room's median pixel
    // is then well above black (the lamp would put it at 1/500 of white).
    const std::vector<float> fused = viz::rainbow_fusion(c);
    const float rainbow_level = viz::reference_level(fused, viz::emitter_pixels(c));
    EXPECT_LE(rainbow_level, 1.1f * 1.0001f);  // the room's brightest pixel: 1 + 0.1
    const size_t n = size_t(kRoomSize) * kRoomSize;
    const std::vector<float> shown =
        viz::tone_map(fused.data(), n, rainbow_level, 0.f, viz::Tone::Linear);
    std::vector<float> room;
    for (int y = 0; y < kRoomSize; ++y)
        for (int x = 0; x < kRoomSize; ++x)
            if (!is_lamp(x, y)) room.push_back(display_max(shown, x, y));
    std::nth_element(room.begin(), room.begin() + ptrdiff_t(room.size() / 2), room.end());
    EXPECT_GT(room[room.size() / 2], 0.5f);
}

TEST(Viz, ExplicitLevelWins) {
    const io::Cube c = room_with_lamp();
    // The lamp's level, given by the user: the room is dim, the lamp still full.
    const std::vector<float> peak = viz::peak_time_image(c, 0, 500.f);
    EXPECT_LT(display_max(peak, 3, 3), 0.35f);
    EXPECT_GT(display_max(peak, 7, 0), 0.99f);
    // Exposure shifts the given level: 500 at +log2(500) stops is a level of 1.
    const std::vector<float> one = viz::peak_time_image(c, 0, 1.f);
    const std::vector<float> shifted = viz::peak_time_image(c, 0, 500.f, std::log2(500.f));
    for (size_t i = 0; i < one.size(); ++i) EXPECT_NEAR(shifted[i], one[i], 1e-5f) << i;
    EXPECT_GT(display_max(one, 3, 3), 0.5f);
}

// ---- files ----------------------------------------------------------------------------------

TEST(Viz, LoadsExrAndNpyCubesAndRejectsOtherFiles) {
    const auto dir = test::temp_dir("viz-load");
    io::Cube c = make_cube(3, 2, 4, 1.5, 0.25);
    for (size_t i = 0; i < c.data.size(); ++i) c.data[i] = float(i);
    c.depth = {1, 2, 3, 4, 5, -1};
    const std::string exr = (dir / "c.exr").string(), npy = (dir / "c.npy").string();
    io::write_exr_cube(exr, 3, 2, 4, c.data.data(), c.depth.data(), c.attributes);
    io::write_npy(npy, {2, 3, 4, 3}, c.data.data());
    const io::Cube a = viz::load_cube(exr), b = viz::load_cube(npy);
    EXPECT_EQ(a.data, c.data);
    EXPECT_EQ(a.depth, c.depth);
    EXPECT_EQ(b.data, c.data);
    EXPECT_TRUE(b.depth.empty());
    EXPECT_DOUBLE_EQ(viz::time_grid(a).start, 1.5);
    EXPECT_FALSE(viz::time_grid(b).known);
    // A steady image is not a cube; a missing file is named.
    const std::string steady = (dir / "s.exr").string();
    io::write_exr_rgb(steady, 3, 2, c.data.data(), {});
    EXPECT_THROW(viz::load_cube(steady), SceneError);
    try {
        viz::load_cube((dir / "gone.exr").string());
        ADD_FAILURE();
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos);
    }
    // Writers: PNG, GIF (several frames), grey EXR.
    const std::vector<float> display(3 * 2 * 3, 0.5f);
    viz::write_png8((dir / "p.png").string(), 3, 2, display);
    viz::write_gif((dir / "a.gif").string(), 3, 2, {display, display, display});
    const std::vector<float> grey = {1, 2, 3, 4, 5, 6};
    viz::write_exr_gray((dir / "g.exr").string(), 3, 2, grey.data(), {{"femto:x", "y"}});
    for (const char* f : {"p.png", "a.gif", "g.exr"})
        EXPECT_GT(std::filesystem::file_size(dir / f), 0u) << f;
    int w = 0, h = 0;
    const std::vector<float> back = io::read_image_rgb((dir / "g.exr").string(), w, h, false);
    EXPECT_EQ(w, 3);
    EXPECT_EQ(back[3 * 5], 6.f);
    std::filesystem::remove_all(dir);
}

// ---- the streak film ------------------------------------------------------------------------

// An orthographic camera at z = 5 over a diffuse plane lit by a point light at height 2; the
// film is `film` (transient or streak) with `filter`. The plane is tilted by 10 degrees about
// y, so that the depth (4.6 to 5.4) varies along a row and across a pixel's filter footprint.
std::string streak_scene(const std::string& film_type, const std::string& extra,
                         const std::string& filter, const std::string& tfilter = "") {
    return "<scene version=\"3.0.0\"><integrator type=\"transient_path\"><integer "
           "name=\"max_depth\" value=\"3\"/></integrator>"
           "<sensor type=\"orthographic\"><transform name=\"to_world\"><scale x=\"3\" y=\"3\"/>"
           "<lookat origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/></transform>"
           "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"4\"/></sampler>"
           "<film type=\"" +
           film_type +
           "\"><integer name=\"width\" value=\"40\"/><integer name=\"height\" value=\"36\"/>"
           "<float name=\"start\" value=\"6.5\"/><float name=\"bin_width\" value=\"0.1\"/>"
           "<integer name=\"bins\" value=\"40\"/>" +
           extra + tfilter + "<rfilter type=\"" + filter +
           "\"/></film></sensor>"
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"2.5\"/>"
           "<rotate y=\"1\" angle=\"10\"/></transform><bsdf type=\"diffuse\"/></shape>"
           "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.5\"/>"
           "<rotate x=\"1\" angle=\"90\"/><translate x=\"1\" z=\"0.5\"/></transform>"
           "<bsdf type=\"diffuse\"/></shape>"
           "<emitter type=\"point\"><point name=\"position\" x=\"0.3\" y=\"-0.2\" z=\"2\"/>"
           "<rgb name=\"intensity\" value=\"4, 3, 2\"/></emitter></scene>";
}

std::string fmt_row(int r) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "_row%04d", r);
    return buf;
}

void expect_close(float a, float b, const std::string& what, double rel = 1e-6) {
    ASSERT_NEAR(a, b, rel * std::max(std::abs(a), std::abs(b)) + 1e-12) << what;
}

// The streak scene rendered with the transient film (DIR/t.exr) and with the streak film
// recording rows 3 and 32 (DIR/s_row0003.exr, DIR/s_row0032.exr), same seed.
struct StreakAndCube {
    std::unique_ptr<Scene> transient, streak;
    std::vector<std::string> streak_files;
};
StreakAndCube render_streak_and_cube(const std::filesystem::path& dir, const std::string& filter,
                                     const std::string& tfilter = "") {
    StreakAndCube r;
    r.transient = load_scene_string(streak_scene("transient", "", filter, tfilter));
    r.streak = load_scene_string(
        streak_scene("streak", "<string name=\"rows\" value=\"32, 3\"/>", filter, tfilter));
    RenderOptions ro;
    ro.seed = 7;
    ro.threads = 2;
    const RenderStats st = render(*r.transient, ro);
    const RenderStats ss = render(*r.streak, ro);
    r.transient->sensor().film().write((dir / "t").string(),
                                       make_render_info(*r.transient, ro, st));
    r.streak_files =
        r.streak->sensor().film().write((dir / "s").string(), make_render_info(*r.streak, ro, ss));
    return r;
}

void check_streak_matches_transient(const std::string& filter, const std::string& tfilter = "") {
    const std::vector<int> rows = {3, 32};  // 32 starts a row of tiles (of 8 or 32 pixels)
    const auto dir = test::temp_dir("streak-" + filter);
    const StreakAndCube both = render_streak_and_cube(dir, filter, tfilter);
    const Film& tf = both.transient->sensor().film();
    const Film& sf = both.streak->sensor().film();
    ASSERT_EQ(tf.width(), 40);
    // Steady images: the recorded rows agree, the others are black.
    const std::vector<float> ti = tf.steady_image(), si = sf.steady_image();
    double energy = 0;
    for (int y = 0; y < 36; ++y)
        for (int x = 0; x < 40; ++x)
            for (int c = 0; c < 3; ++c) {
                const size_t i = (size_t(y) * 40 + size_t(x)) * 3 + size_t(c);
                if (y == 3 || y == 32) {
                    expect_close(si[i], ti[i], filter + " steady row " + std::to_string(y));
                    energy += si[i];
                } else {
                    ASSERT_EQ(si[i], 0.f) << y;
                }
            }
    EXPECT_GT(energy, 0.0);
    // Per bin: the EXR outputs read back.
    const std::string tbase = (dir / "t").string(), sbase = (dir / "s").string();
    ASSERT_EQ(both.streak_files.size(), 4u);
    const io::Cube cube = io::read_exr_cube(tbase + ".exr");
    ASSERT_EQ(cube.depth.size(), size_t(40 * 36));
    for (int r : rows) {
        const std::string exr = sbase + fmt_row(r) + ".exr";
        ASSERT_TRUE(std::filesystem::exists(sbase + fmt_row(r) + ".png"));
        int w = 0, h = 0;
        const std::vector<float> img = io::read_image_rgb(exr, w, h, false);
        ASSERT_EQ(w, 40);
        ASSERT_EQ(h, 40);  // bins
        const std::vector<float> slice = viz::streak_slice(cube, r);
        double sum = 0;
        for (size_t i = 0; i < img.size(); ++i) {
            expect_close(img[i], slice[i], filter + " row " + std::to_string(r));
            sum += img[i];
        }
        EXPECT_GT(sum, 0.0);
        // The depth (channel Z) is the cube's depth row: the same sums of the same samples.
        const io::Cube s = viz::load_cube(exr);
        ASSERT_TRUE(viz::is_streak(s));
        ASSERT_EQ(s.height, 1);
        ASSERT_EQ(s.depth.size(), 40u);
        EXPECT_EQ(*s.attribute("femto:row"), std::to_string(r));
        int hit = 0;
        float zmin = 1e30f, zmax = 0;
        for (int x = 0; x < 40; ++x) {
            const float z = cube.depth[size_t(r) * 40 + size_t(x)];
            expect_close(s.depth[size_t(x)], z, filter + " depth row " + std::to_string(r));
            if (z > 0) {
                ++hit;
                zmin = std::min(zmin, z);
                zmax = std::max(zmax, z);
            }
        }
        EXPECT_GT(hit, 20);
        EXPECT_GT(zmax - zmin, 0.5f);  // the tilted plane
        // The PNG preview is that of the RGB image.
        const std::string ref = (dir / "ref.png").string();
        io::write_png_preview(ref, 40, 40, slice.data());
        int pw = 0, ph = 0, rw = 0, rh = 0;
        const std::vector<float> png =
            io::read_image_rgb(sbase + fmt_row(r) + ".png", pw, ph, false);
        const std::vector<float> want = io::read_image_rgb(ref, rw, rh, false);
        ASSERT_EQ(pw, 40);
        ASSERT_EQ(ph, 40);
        ASSERT_EQ(png.size(), want.size());
        for (size_t i = 0; i < png.size(); ++i) ASSERT_NEAR(png[i], want[i], 1.01 / 255) << i;
    }
    EXPECT_EQ(*cube.attribute("femto:bins"), "40");
    std::filesystem::remove_all(dir);
}

TEST(StreakFilm, EqualsTransientRowsBoxFilter) { check_streak_matches_transient("box"); }
// The kernel filter's pilot samples each pixel of the recorded rows with the same random
// streams in both films, so the bandwidths, and then the rows, agree.
TEST(StreakFilm, EqualsTransientRowsKernelFilter) {
    check_streak_matches_transient("gaussian",
                                   "<tfilter type=\"kernel\"><integer name=\"pilot_spp\" "
                                   "value=\"8\"/><integer name=\"k_neighbors\" value=\"5\"/>"
                                   "</tfilter>");
}
TEST(StreakFilm, EqualsTransientRowsGaussianFilter) { check_streak_matches_transient("gaussian"); }

// Unwarping a streak image gives the corresponding row of the unwarped cube: the same depth
// shifts the same series. Each output window is the bins that hold its energy, so the two are
// compared on the common time grid. (Keeping the input's window would drop everything here:
// the scene's world times lie a camera distance, 5, before the window.)
TEST(StreakFilm, UnwarpEqualsUnwarpedCubeRow) {
    const auto dir = test::temp_dir("streak-unwarp");
    render_streak_and_cube(dir, "gaussian");
    const io::Cube cube = viz::load_cube((dir / "t.exr").string());
    ASSERT_FALSE(viz::is_streak(cube));
    const viz::UnwarpResult cw = viz::unwarp(cube, viz::time_grid(cube), true);
    const double bw = viz::time_grid(cube).bin_width, cs = start_of(cw.cube);
    for (int r : {3, 32}) {
        const io::Cube s = viz::load_cube((dir / ("s" + fmt_row(r) + ".exr")).string());
        const viz::UnwarpResult sw = viz::unwarp(s, viz::time_grid(s), true);
        ASSERT_TRUE(viz::is_streak(sw.cube));
        EXPECT_EQ(*sw.cube.attribute("femto:time"), "world");
        EXPECT_EQ(*sw.cube.attribute("femto:row"), std::to_string(r));
        // Streak bin j - k is cube bin j (both grids keep the input's alignment).
        const double ks = (start_of(sw.cube) - cs) / bw;
        const long k = std::lround(ks);
        ASSERT_NEAR(ks, double(k), 1e-6);
        ASSERT_GE(k, 0);  // the cube's window holds every row's energy
        ASSERT_LE(k + sw.cube.bins, cw.cube.bins);
        const std::string what = "row " + std::to_string(r);
        double energy = 0;
        for (int x = 0; x < 40; ++x) {
            expect_close(sw.cube.depth[size_t(x)], cw.cube.depth[size_t(r) * 40 + size_t(x)],
                         what + " depth");
            for (int j = 0; j < cw.cube.bins; ++j) {  // every bin of the cube's row
                const long js = long(j) - k;
                for (int ch = 0; ch < 3; ++ch) {
                    const float cv =
                        cw.cube.data[((size_t(r) * 40 + size_t(x)) * size_t(cw.cube.bins) +
                                      size_t(j)) *
                                         3 +
                                     size_t(ch)];
                    const float sv =
                        js >= 0 && js < sw.cube.bins
                            ? sw.cube.data[(size_t(x) * size_t(sw.cube.bins) + size_t(js)) * 3 +
                                           size_t(ch)]
                            : 0.f;
                    expect_close(sv, cv, what + " x " + std::to_string(x), 2e-6);
                    energy += sv;
                }
            }
        }
        EXPECT_GT(energy, 0.0) << what;
        // What `femto viz unwarp` writes for a streak image reads back as the same image.
        const std::string out = (dir / ("w" + fmt_row(r) + ".exr")).string();
        viz::write_streak_exr(out, sw.cube, 0, sw.cube.attributes);
        const io::Cube back = viz::load_cube(out);
        EXPECT_TRUE(viz::is_streak(back));
        EXPECT_EQ(back.data, sw.cube.data);
        EXPECT_EQ(back.depth, sw.cube.depth);
        EXPECT_EQ(*back.attribute("femto:start"), *sw.cube.attribute("femto:start"));
        EXPECT_EQ(*back.attribute("femto:time"), "world");
    }
    std::filesystem::remove_all(dir);
}

// Both time-resolved films splat through TimeResolvedBlock: a camera sample with a NaN,
// infinite or negative radiance adds nothing, not even its filter weight, and each bad
// contribution is counted by its kind.
TEST(StreakFilm, RejectsBadSamplesAsTheTransientFilm) {
    for (const std::string type : {"transient", "streak"}) {
        auto scene = load_scene_string(streak_scene(
            type, type == "streak" ? "<integer name=\"row\" value=\"3\"/>" : "", "box"));
        Film& film = scene->sensor().film();
        const auto* trf = dynamic_cast<const TimeResolvedFilm*>(&film);
        ASSERT_NE(trf, nullptr) << type;
        ContributionList good, nan, inf, negative;
        good.add(Color(1.f), 7.0);  // bin 5 of [6.5, 10.5)
        nan.add(Color(1.f), 7.0);
        nan.add(Color(std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f), 7.0);
        inf.add(Color(0.f, std::numeric_limits<float>::infinity(), 0.f), 7.0);
        negative.add(Color(1.f, -1e-6f, 1.f), 7.0);
        negative.add(Color(0.f, 0.f, -2.f), 8.0);
        auto block = film.make_block(0, 0, 8, 8);
        for (const ContributionList* sample : {&nan, &good, &inf, &negative})
            block->put(Vec2{2.5f, 3.5f}, *sample);  // the box filter: pixel (2, 3) alone
        film.merge(*block);
        const RejectedContributions r = trf->rejected();
        EXPECT_EQ(r.nan, 1u) << type;
        EXPECT_EQ(r.infinite, 1u) << type;
        EXPECT_EQ(r.negative, 2u) << type;
        const std::vector<float> img = film.steady_image();
        for (int c = 0; c < 3; ++c) EXPECT_EQ(img[(3 * 40 + 2) * 3 + size_t(c)], 1.f) << type;
    }
}

// A progressive render adds one pass at a time into the film's float totals. Rounded to
// nearest, a voxel that receives the same value every pass drifts: after 2^18 passes the
// value (0.7, 1.3, 0.1) came out 2.6e-3 too high in red (the error grows with n). Passes
// after the 64th add by stochastic rounding (add_without_drift()), whose error is zero-mean
// with a standard deviation of about 2^-24 sqrt(n / 3) of the total: 1.8e-5 at n = 2^18. The
// bound, 1e-4, is 5.5 of those; the nearest-rounded sum misses it by 25x. Both films, and the
// same bits for the same passes.
TEST(TransientFilm, ManyPassesOfTheSameValueDoNotDrift) {
    constexpr uint32_t kPasses = 1u << 18;
    const Color value(0.7f, 1.3f, 0.1f);
    for (const std::string type : {"transient", "streak"}) {
        SCOPED_TRACE(type);
        std::vector<float> images[2];
        for (std::vector<float>& img : images) {
            auto scene = load_scene_string(streak_scene(
                type, type == "streak" ? "<integer name=\"row\" value=\"3\"/>" : "", "box"));
            Film& film = scene->sensor().film();
            ContributionList sample;
            sample.add(value, 7.0);  // bin 5
            for (uint32_t pass = 0; pass < kPasses; ++pass) {
                film.start_pass(pass);
                auto block = film.make_block(0, 0, 8, 8);
                block->put(Vec2{2.5f, 3.5f}, sample);  // the box filter: pixel (2, 3) alone
                film.merge(*block);
            }
            img = film.steady_image();
        }
        for (int c = 0; c < 3; ++c) {
            const float got = images[0][(3 * 40 + 2) * 3 + size_t(c)];
            EXPECT_NEAR(got / value[c], 1.0, 1e-4) << "channel " << c;
            EXPECT_EQ(got, images[1][(3 * 40 + 2) * 3 + size_t(c)]) << "channel " << c;
        }
    }
}

// A transient block keeps one entry per (pixel, bin) it received, found through the run of
// the pixel being splatted or, once a pixel receives again after its run, through a table that
// grows with them; its storage is recycled for the next block. Whatever their number and
// order (pixel by pixel, in any order, or first one then the other), and after a block that
// was dropped unmerged (an exception), each cube entry is its contributions summed in one
// double in the order they came, rounded to float once per merge (values of every float digit:
// an entry split in two, or a stale one, rounds differently), and the count AOV and the pixels'
// filter weights are those of the merged samples alone.
TEST(TransientFilm, BlocksSumEveryContributionThroughGrowthAndRecycling) {
    for (const bool with_count : {true, false}) {
        SCOPED_TRACE(with_count ? "aovs=count" : "no AOV");
        auto scene = load_scene_string(streak_scene(
            "transient", with_count ? "<string name=\"aovs\" value=\"count\"/>" : "", "box"));
        Film& film = scene->sensor().film();
        const size_t W = 40, H = 36, bins = 40;  // streak_scene's film: bins of 0.1 from 6.5
        std::vector<float> want(W * H * bins * 3, 0.f), want_count(W * H * bins, 0.f);
        std::vector<double> want_weight(W * H, 0.0);
        std::mt19937 rng(7);
        std::uniform_real_distribution<float> value(0.01f, 1.f);
        // `runs` of the block's samples come pixel by pixel (as a tile's camera samples do),
        // the rest at random pixels.
        auto round = [&](int samples, int runs, bool merged) {
            std::vector<double> block_sums(want.size(), 0.0);  // the block's sums, one per entry
            std::vector<float> block_count(want_count.size(), 0.f);
            std::vector<double> block_weight(want_weight.size(), 0.0);
            auto block = film.make_block(0, 0, 8, 8);
            for (int s = 0; s < samples; ++s) {
                const size_t in_run = size_t(s) * 64 / size_t(std::max(runs, 1));
                const size_t x = s < runs ? in_run % 8 : rng() % 8,
                             y = s < runs ? in_run / 8 : rng() % 8, pixel = y * W + x;
                ContributionList sample;
                for (int n = int(rng() % 3) + 1; n > 0; --n) {  // may repeat a bin in a sample
                    const int bin = int(rng() % uint32_t(bins + 2)) - 1;  // -1 and 40: outside
                    const float k = value(rng);
                    const Color radiance(k, 2 * k, 3 * k);
                    sample.add(radiance, 6.5 + (bin + 0.5) * 0.1);
                    if (bin < 0 || bin >= int(bins)) continue;
                    const size_t at = pixel * bins + size_t(bin);
                    for (int c = 0; c < 3; ++c) block_sums[at * 3 + size_t(c)] += radiance[c];
                    block_count[at] += 1.f;
                }
                block_weight[pixel] += 1.0;  // the box filter: weight 1 in the sample's pixel
                block->put(Vec2{float(x) + 0.5f, float(y) + 0.5f}, sample);
            }
            if (!merged) return;
            film.merge(*block);
            for (size_t i = 0; i < want.size(); ++i) want[i] += float(block_sums[i]);
            for (size_t i = 0; i < want_count.size(); ++i) want_count[i] += block_count[i];
            for (size_t i = 0; i < want_weight.size(); ++i) want_weight[i] += block_weight[i];
        };
        round(20000, 0, true);     // 8 x 8 pixels x 40 bins, nearly all touched: the table grows
        round(3000, 0, false);     // dropped: must leave nothing behind in the recycled storage
        round(6400, 6400, true);   // pixel by pixel: 100 samples each, no table
        round(3000, 1500, false);  // runs, then the table (dropped)
        round(6400, 3200, true);   // half the pixels' runs, then the table for all of them
        round(500, 0, true);
        const std::vector<Accumulator> acc = film.accumulators();  // cube, count, sq, weights
        ASSERT_EQ(acc[0].count, want.size());
        ASSERT_EQ(acc[1].count, with_count ? want_count.size() : 0u);
        ASSERT_EQ(acc[3].count, want_weight.size() * sizeof(PixelSums) / sizeof(double));
        const auto* cube = static_cast<const float*>(acc[0].data);
        const auto* count = static_cast<const float*>(acc[1].data);
        const auto* sums = static_cast<const PixelSums*>(acc[3].data);
        size_t wrong = 0, wrong_count = 0, wrong_weight = 0;
        for (size_t i = 0; i < want.size(); ++i) wrong += cube[i] != want[i] ? 1 : 0;
        if (with_count)
            for (size_t i = 0; i < want_count.size(); ++i) wrong_count += count[i] != want_count[i];
        for (size_t p = 0; p < want_weight.size(); ++p)
            wrong_weight += sums[p].weight != want_weight[p];
        EXPECT_EQ(wrong, 0u);
        EXPECT_EQ(wrong_count, 0u);
        EXPECT_EQ(wrong_weight, 0u);
        // More entries than the storage's first table holds (4096 slots at a load of 1/2).
        EXPECT_GT(
            std::count_if(want_count.begin(), want_count.end(), [](float n) { return n > 0; }),
            2048);
    }
}

TEST(StreakFilm, SkipsRowsOutsideTheFootprint) {
    auto scene =
        load_scene_string(streak_scene("streak", "<integer name=\"row\" value=\"10\"/>", "box"));
    const Film& f = scene->sensor().film();
    for (int y = 0; y < 36; ++y)
        EXPECT_EQ(f.row_active(y), y == 10 || y == 11) << y;  // box: pos.y in [10, 11]
    auto wide = load_scene_string(
        streak_scene("streak", "<integer name=\"row\" value=\"10\"/>", "gaussian"));
    EXPECT_TRUE(wide->sensor().film().row_active(8));
    EXPECT_TRUE(wide->sensor().film().row_active(12));
    EXPECT_FALSE(wide->sensor().film().row_active(5));
    EXPECT_FALSE(wide->sensor().film().row_active(15));
    EXPECT_EQ(f.max_time(), 6.5 + 4.0);
}

TEST(StreakFilm, RejectsBadRows) {
    auto error = [](const std::string& extra) {
        return test::load_error(streak_scene("streak", extra, "box"));
    };
    EXPECT_NE(error("").find("needs the rows"), std::string::npos);
    EXPECT_NE(error("<string name=\"rows\" value=\"3, 36\"/>").find("outside the image"),
              std::string::npos);
    EXPECT_NE(error("<integer name=\"row\" value=\"-1\"/>").find("outside the image"),
              std::string::npos);
    EXPECT_NE(error("<string name=\"rows\" value=\"3, 4, 3\"/>").find("given twice"),
              std::string::npos);
    EXPECT_NE(error("<string name=\"rows\" value=\"\"/>").find("comma-separated"),
              std::string::npos);
    EXPECT_NE(error("<string name=\"rows\" value=\"3,,4\"/>").find("comma-separated"),
              std::string::npos);
    EXPECT_NE(error("<string name=\"rows\" value=\"3\"/><integer name=\"row\" value=\"3\"/>")
                  .find("not both"),
              std::string::npos);
}

TEST(VizAttributes, NumbersAreWrittenShortestRoundTrip) {
    // 0.05 is written "0.05", not "0.050000000000000003", and reads back to the same double.
    TimeGrid grid;
    grid.start = 0.05;
    grid.bin_width = 0.1;
    grid.bins = 7;
    grid.length_unit = "mm";
    const io::Attributes attrs = io::time_resolved_attributes(grid, RenderInfo{}, "histogram");
    auto value = [&](const std::string& name) {
        for (const auto& [k, v] : attrs)
            if (k == name) return v;
        ADD_FAILURE() << name << " missing";
        return std::string();
    };
    EXPECT_EQ(value("femto:start"), "0.05");
    EXPECT_EQ(value("femto:bin_width"), "0.1");
    EXPECT_EQ(std::stod(value("femto:start_ps")), grid.to_picoseconds(0.05));
}
