// Rendering against physics: the furnace, a point light over a Lambertian plane, determinism
// and the stop flag.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <numeric>
#include <thread>

#include "femto/integrator.h"
#include "femto/sensor.h"
#include "femto/testing/render.h"
#include "render/tiles.h"
#include "scene_util.h"

using namespace femto;

namespace {

std::string furnace_scene(double albedo, double radiance, const std::string& integrator) {
    return "<scene version=\"3.0.0\">" + integrator +
           "<sensor type=\"perspective\"><float name=\"fov\" value=\"60\"/>"
           "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"16\"/></sampler>"
           "<film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" "
           "value=\"32\"/>"
           "<rfilter type=\"box\"/></film></sensor>"
           "<shape type=\"sphere\"><float name=\"radius\" value=\"3\"/><boolean "
           "name=\"flip_normals\" value=\"true\"/>"
           "<bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"" +
           std::to_string(albedo) +
           "\"/></bsdf>"
           "<emitter type=\"area\"><float name=\"radiance\" value=\"" +
           std::to_string(radiance) +
           "\"/></emitter>"
           "</shape></scene>";
}

}  // namespace

TEST(Render, FurnaceMatchesGeometricSeries) {
    // Inside a closed diffuse sphere of albedo rho emitting Le everywhere, L = Le / (1 - rho).
    for (double rho : {0.3, 0.7}) {
        auto scene = load_scene_string(furnace_scene(
            rho, 1.0,
            "<integrator type=\"path\"><integer name=\"max_depth\" value=\"-1\"/></integrator>"));
        RenderOptions opt;
        opt.seed = 7;
        render(*scene, opt);
        const femto::testing::MeanAndError s =
            femto::testing::pixel_mean(scene->sensor().film().steady_image(), 1);
        const double expected = 1.0 / (1.0 - rho);
        EXPECT_GT(s.standard_error, 0.0);
        EXPECT_NEAR(s.mean, expected, 3 * s.standard_error + 1e-6 * expected)
            << "rho=" << rho << " standard error " << s.standard_error;
    }
}

TEST(Render, WorldTimeWindowEndsUnboundedPaths) {
    // In a closed sphere nothing but the film's window ends a path of transient_path with
    // max_depth -1 (no roulette). In world time the window's end is known in camera time only
    // from the first vertex on (end + sensor distance): the render must finish, and equal the
    // one with a depth limit far beyond the window (paths of 200 segments of >= 0.1 in a
    // sphere of radius 3 outlast a window of 10), with the same random numbers.
    auto scene_with = [](int depth) {
        std::string xml = furnace_scene(
            0.9, 1.0,
            "<integrator type=\"transient_path\"><integer name=\"max_depth\" value=\"" +
                std::to_string(depth) + "\"/></integrator>");
        const std::string steady = "<film type=\"hdrfilm\">";
        xml.replace(xml.find(steady), steady.size(),
                    "<film type=\"transient\"><float name=\"bin_width\" value=\"0.5\"/>"
                    "<integer name=\"bins\" value=\"20\"/><boolean name=\"world_time\" "
                    "value=\"true\"/>");
        return load_scene_string(xml);
    };
    auto unbounded = scene_with(-1), bounded = scene_with(200);
    femto::testing::expect_same_image(femto::testing::render_steady(*bounded, 3),
                                      femto::testing::render_steady(*unbounded, 3), "max_depth 200",
                                      "max_depth -1");
}

// The direct integrator's sample counts are bounded: a camera sample keeps one contribution
// per emitter and BSDF sample in memory, so 2^31 of them asked for ~100 GB (a sweep of bad
// values found it). Each bad count is an error at its own parameter's line.
TEST(Render, DirectSampleCountsOutsideTheirRangeAreLocatedErrors) {
    for (const char* name : {"shading_samples", "emitter_samples", "bsdf_samples"})
        for (const char* value : {"-1", "65537", "2147483648"}) {
            SCOPED_TRACE(std::string(name) + " = " + value);
            const std::string xml =
                std::string("<scene version=\"3.0.0\">\n<integrator type=\"direct\">\n") +
                "<integer name=\"" + name + "\" value=\"" + value +
                "\"/>\n</integrator>\n</scene>\n";
            const std::string error = femto::test::load_error(xml);
            EXPECT_NE(error.find(":3:"), std::string::npos) << error;
            EXPECT_NE(error.find(std::string(name) + " must be in [0, 65536], got " + value),
                      std::string::npos)
                << error;
        }
    EXPECT_NO_THROW(load_scene_string(
        "<scene version=\"3.0.0\"><integrator type=\"direct\">"
        "<integer name=\"emitter_samples\" value=\"65536\"/>"
        "</integrator><sensor type=\"perspective\"/><emitter type=\"constant\"/></scene>"));
}

TEST(Render, PointLightOverLambertianPlane) {
    // L(x) = rho/pi * I * cos(theta) / d^2 with cos(theta) = h/d, viewed orthographically.
    const double I = 5, h = 1.5, rho = 0.6;
    const std::string xml =
        "<scene version=\"3.0.0\"><integrator type=\"direct\"/>"
        "<sensor type=\"orthographic\"><transform name=\"to_world\"><scale x=\"2\" y=\"2\"/>"
        "<lookat origin=\"0,0,5\" target=\"0,0,0\" up=\"0,1,0\"/></transform>"
        "<sampler type=\"independent\"><integer name=\"sample_count\" value=\"64\"/></sampler>"
        "<film type=\"hdrfilm\"><integer name=\"width\" value=\"16\"/><integer name=\"height\" "
        "value=\"16\"/>"
        "<rfilter type=\"box\"/></film></sensor>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"10\"/></transform>"
        "<bsdf type=\"diffuse\"><float name=\"reflectance\" value=\"0.6\"/></bsdf></shape>"
        "<emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"0\" z=\"1.5\"/>"
        "<float name=\"intensity\" value=\"5\"/></emitter></scene>";
    auto scene = load_scene_string(xml);
    RenderOptions opt;
    opt.seed = 3;
    render(*scene, opt);
    const auto img = scene->sensor().film().steady_image();
    const Sensor& sensor = scene->sensor();
    auto radiance_at = [&](Vec2 pos) {
        const Ray r = sensor.sample_ray(pos, {});
        const double t = -double(r.o.z) / r.d.z;
        const double x = r.o.x + t * r.d.x, y = r.o.y + t * r.d.y;
        const double d2 = x * x + y * y + h * h;
        return rho / M_PI * I * (h / std::sqrt(d2)) / d2;
    };
    const int spp = 64, grid = 32;
    for (int py = 0; py < 16; ++py)
        for (int px = 0; px < 16; ++px) {
            // The estimate averages L over uniformly jittered positions in the pixel: compare
            // with the pixel average, allowing 4 standard errors of that jitter.
            double sum = 0, sum2 = 0;
            for (int j = 0; j < grid; ++j)
                for (int i = 0; i < grid; ++i) {
                    const double v = radiance_at({px + (i + 0.5f) / grid, py + (j + 0.5f) / grid});
                    sum += v;
                    sum2 += v * v;
                }
            const double mean = sum / (grid * grid);
            const double sd = std::sqrt(std::max(0.0, sum2 / (grid * grid) - mean * mean));
            const double tol = 4 * sd / std::sqrt(double(spp)) + 1e-5 * mean;
            EXPECT_NEAR(img[3 * (py * 16 + px)], mean, tol) << "pixel " << px << "," << py;
        }
}

TEST(Render, DeterministicForSeedAndThreads) {
    const std::string xml = femto::test::scene_xml(
        "<shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0\" z=\"4\"/>"
        "<emitter type=\"area\"><float name=\"radiance\" value=\"2\"/></emitter></shape>"
        "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"5\"/><translate "
        "z=\"6\"/></transform></shape>");
    auto render_with = [&](int threads, uint64_t seed) {
        auto scene = load_scene_string(xml);
        RenderOptions opt;
        opt.threads = threads;
        opt.seed = seed;
        opt.spp = 8;
        render(*scene, opt);
        return scene->sensor().film().steady_image();
    };
    const auto a = render_with(2, 1), b = render_with(2, 1), c = render_with(1, 1),
               d = render_with(2, 2);
    EXPECT_EQ(a, b);  // bit for bit
    EXPECT_EQ(a, c);  // the tile merge order makes it independent of the thread count too
    EXPECT_NE(a, d);  // and the seed matters
}

namespace {

// Every sum a film keeps (the cube, the pixels' weights), byte for byte, after a render of
// `xml` at `spp` in an arena of `threads`.
// `stop` and `stats`, when given: the render's stop flag and what it reports.
std::string film_sums(const std::string& xml, int threads, uint32_t spp,
                      const std::atomic<bool>* stop = nullptr, RenderStats* stats = nullptr) {
    auto scene = load_scene_string(xml);
    RenderOptions opt;
    opt.threads = threads;
    opt.spp = spp;
    opt.stop = stop;
    tbb::task_arena(threads).execute([&] {
        const RenderStats s = render(*scene, opt);
        if (stats) *stats = s;
    });
    std::string bytes;
    for (const Accumulator& a : scene->sensor().film().accumulators())
        bytes.append(static_cast<const char*>(a.data), a.count * a.element_bytes());
    return bytes;
}

const std::string kOverlapBody =
    "<shape type=\"sphere\"><point name=\"center\" x=\"0.3\" y=\"-0.2\" z=\"4\"/>"
    "<emitter type=\"area\"><float name=\"radiance\" value=\"2\"/></emitter></shape>"
    "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"5\"/><translate "
    "z=\"6\"/></transform></shape>";
const std::string kGaussianHdrFilm =
    "<film type=\"hdrfilm\"><integer name=\"width\" value=\"160\"/><integer "
    "name=\"height\" value=\"96\"/><rfilter type=\"gaussian\"/></film>";
const std::string kGaussianCubeFilm =
    "<film type=\"transient\"><integer name=\"width\" value=\"64\"/><integer "
    "name=\"height\" value=\"48\"/><float name=\"start\" value=\"0\"/><float "
    "name=\"bin_width\" value=\"0.5\"/><integer name=\"bins\" value=\"40\"/><rfilter "
    "type=\"gaussian\"/></film>";

}  // namespace

// A pass's threads share its tiles, so a film has at least 64 (that meet rows it records) where
// 8-pixel tiles allow it (a 32x32 film in 32-pixel tiles was one tile: one busy thread on any
// machine); a transient cube's blocks shrink its tiles further (1/32 of the film at most); a
// wide filter keeps them at twice its radius at least.
TEST(Render, TilesAreManyEnoughForThreadsToShare) {
    auto tile = [](const std::string& film) {
        return detail::tile_size_for(
            load_scene_string(femto::test::scene_xml("<sensor type=\"perspective\">" + film +
                                                     "</sensor>" + femto::test::kRect))
                ->sensor()
                .film());
    };
    auto hdr = [](int w, int h, const std::string& rfilter = "<rfilter type=\"box\"/>") {
        return "<film type=\"hdrfilm\"><integer name=\"width\" value=\"" + std::to_string(w) +
               "\"/><integer name=\"height\" value=\"" + std::to_string(h) + "\"/>" + rfilter +
               "</film>";
    };
    EXPECT_EQ(tile(hdr(32, 32)), 8);     // 16 tiles: 8 pixels is the smallest side
    EXPECT_EQ(tile(hdr(64, 64)), 8);     // 64 tiles
    EXPECT_EQ(tile(hdr(128, 128)), 16);  // 64
    EXPECT_EQ(tile(hdr(100, 60)), 8);    // 13 x 8 = 104 (16-pixel tiles: 7 x 4 = 28)
    EXPECT_EQ(tile(hdr(256, 256)), 32);  // 64
    EXPECT_EQ(tile(hdr(1920, 1080)), 32);
    EXPECT_EQ(tile(hdr(4, 4)), 8);
    // A Gaussian of radius 2 still allows 8; one of radius 12 needs tiles of 24 or more.
    EXPECT_EQ(tile(hdr(64, 64, "<rfilter type=\"gaussian\"/>")), 8);
    EXPECT_EQ(tile(hdr(64, 64,
                       "<rfilter type=\"gaussian\"><float name=\"stddev\" value=\"3\"/>"
                       "</rfilter>")),
              32);
    // Cubes of 40 bins: at 64x64 with a tent (border 1), 8-pixel tiles, whose blocks of
    // (8 + 2)^2 = 100 pixels fit in 64 x 64 / 32 = 128; at 32x32 with a box, 4 (a block of
    // 8^2 = 64 pixels would exceed 32 x 32 / 32 = 32).
    EXPECT_EQ(tile("<film type=\"transient\"><integer name=\"width\" value=\"64\"/><integer "
                   "name=\"height\" value=\"64\"/><float name=\"start\" value=\"0\"/><float "
                   "name=\"bin_width\" value=\"0.5\"/><integer name=\"bins\" value=\"40\"/>"
                   "<rfilter type=\"tent\"/></film>"),
              8);
    EXPECT_EQ(tile(femto::test::box_transient_film(32, 32, 0, 0.5, 40)), 4);
    // Only tiles that meet a recorded row count: a 256x256 streak film of one row has 8 such
    // 32-pixel tiles, and 32 of 8 pixels.
    EXPECT_EQ(tile("<film type=\"streak\"><integer name=\"width\" value=\"256\"/><integer "
                   "name=\"height\" value=\"256\"/><integer name=\"row\" value=\"100\"/>"
                   "<float name=\"start\" value=\"0\"/><float name=\"bin_width\" "
                   "value=\"0.5\"/><integer name=\"bins\" value=\"40\"/></film>"),
              8);
}

// Many tiles whose Gaussian filter borders overlap (8-pixel tiles in the hdrfilm, 4 in the
// cube): the tiles of a pass run without a barrier between colours, and each block merges only
// after the overlapping blocks of earlier colours, so a pixel sums its blocks in one order at any
// thread count. An arena of 8 threads on fewer cores shuffles which tile finishes first (the
// renderer's workers are as many as its arena's concurrency).
TEST(Render, SameImageAtAnyThreadCountWithOverlappingTiles) {
    for (const std::string& film : std::vector<std::string>{
             kGaussianHdrFilm, kGaussianCubeFilm,
             // The kernel's pilot in the image: its 2 samples merge as each tile's pilot is done.
             "<film type=\"transient\"><integer name=\"width\" value=\"64\"/><integer "
             "name=\"height\" value=\"48\"/><float name=\"start\" value=\"0\"/><float "
             "name=\"bin_width\" value=\"0.5\"/><integer name=\"bins\" value=\"40\"/><rfilter "
             "type=\"gaussian\"/><tfilter type=\"kernel\"><integer name=\"pilot_spp\" "
             "value=\"2\"/></tfilter></film>"}) {
        const std::string xml = femto::test::scene_xml("<sensor type=\"perspective\">" + film +
                                                       "</sensor>" + kOverlapBody);
        const auto one = film_sums(xml, 1, 4);
        ASSERT_GT(one.size(), 160u * 96 * 3 * 4 / 2) << film;  // the image's sums are there
        EXPECT_TRUE(film_sums(xml, 2, 4) == one) << film;      // bit for bit
        for (int run = 0; run < 3; ++run) EXPECT_TRUE(film_sums(xml, 8, 4) == one) << film;
    }
}

// An integrator that splats (BDPT) runs the same tile loop, each tile's splats kept until the
// pass's last tile and merged then in tile order: the same bits at any thread count, over
// several passes (16 spp: four passes of 4 spp at 160x96, whose passes take at most 65,536
// camera samples, and two of 8 in the 64x48 cube).
TEST(Render, SplatsGiveTheSameImageAtAnyThreadCount) {
    for (const std::string& film : {kGaussianHdrFilm, kGaussianCubeFilm}) {
        const std::string xml = femto::test::scene_xml(
            "<integrator type=\"transient_bdpt\"><integer name=\"max_depth\" "
            "value=\"3\"/></integrator><sensor type=\"perspective\">" +
            film + "</sensor>" + kOverlapBody);
        const auto one = film_sums(xml, 1, 16);
        ASSERT_FALSE(one.empty()) << film;
        EXPECT_TRUE(film_sums(xml, 2, 16) == one) << film;  // bit for bit
        EXPECT_TRUE(film_sums(xml, 8, 16) == one) << film;
    }
}

// On a film of more pixels than a splatting pass's 65,536 camera samples, a pass is one sample
// per pixel whose splats merge after each group of tiles: still the same image at any thread
// count. (320x224: 71,680 pixels, 70 tiles, two groups.)
TEST(Render, SplatGroupsGiveTheSameImageAtAnyThreadCount) {
    const std::string xml = femto::test::scene_xml(
        "<integrator type=\"bdpt\"><integer name=\"max_depth\" value=\"3\"/></integrator>"
        "<sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" "
        "value=\"320\"/><integer name=\"height\" value=\"224\"/><rfilter "
        "type=\"gaussian\"/></film></sensor>" +
        kOverlapBody);
    const auto one = film_sums(xml, 1, 2);
    ASSERT_FALSE(one.empty());
    EXPECT_TRUE(film_sums(xml, 2, 2) == one);  // bit for bit
    EXPECT_TRUE(film_sums(xml, 8, 2) == one);
}

// A stop request ends a splatting render at the end of a pass: its splats reach every pixel
// and are normalised by each pixel's camera samples, so a pass stopped midway would leave
// tile-sized steps in the image. Whenever the request comes, the render holds whole passes
// (4 spp each here: 160x96 pixels, 65,536 / 15,360 rounded down) and equals, bit for bit, a
// render asked for that many samples (same passes).
TEST(Render, StoppedSplattingRenderKeepsWholePasses) {
    const std::string xml = femto::test::scene_xml(
        "<integrator type=\"bdpt\"><integer name=\"max_depth\" value=\"3\"/></integrator>"
        "<sensor type=\"perspective\">" +
        kGaussianHdrFilm + "</sensor>" + kOverlapBody);
    constexpr uint32_t kSpp = 64, kPassSpp = 4;
    const auto t0 = std::chrono::steady_clock::now();
    const std::string full = film_sums(xml, 2, kSpp);
    const auto seconds = std::chrono::steady_clock::now() - t0;
    std::atomic<bool> stop{false};
    RenderStats stats;
    std::thread stopper([&] {  // about a third into the render: in the middle of a pass
        std::this_thread::sleep_for(seconds / 3);
        stop = true;
    });
    const std::string stopped = film_sums(xml, 2, kSpp, &stop, &stats);
    stopper.join();
    EXPECT_EQ(stats.spp_done % kPassSpp, 0u) << stats.spp_done;
    if (stats.spp_done == kSpp) {
        EXPECT_TRUE(stopped == full);
    } else if (stats.spp_done > 0) {
        EXPECT_TRUE(stats.interrupted);
        EXPECT_TRUE(stopped == film_sums(xml, 2, stats.spp_done)) << stats.spp_done;
    }
}

// The kernel filter's pilot is, by default, the image's first samples: a render costs the
// image's samples alone (a separate pilot of as many samples doubles the paths), reports no
// pilot time, and stops like any pass.
TEST(Render, KernelPilotInTheImageCostsNoExtraPaths) {
    auto xml = [](const std::string& in_image) {
        return femto::test::scene_xml(
            "<sensor type=\"perspective\"><film type=\"transient\"><integer name=\"width\" "
            "value=\"32\"/><integer name=\"height\" value=\"24\"/><float name=\"start\" "
            "value=\"0\"/><float name=\"bin_width\" value=\"0.5\"/><integer name=\"bins\" "
            "value=\"40\"/><tfilter type=\"kernel\"><integer name=\"pilot_spp\" "
            "value=\"8\"/><boolean name=\"pilot_in_image\" value=\"" +
            in_image +
            "\"/></tfilter></film></sensor>"
            "<shape type=\"sphere\"><point name=\"center\" x=\"0.3\" y=\"-0.2\" z=\"4\"/>"
            "<emitter type=\"area\"><float name=\"radiance\" value=\"2\"/></emitter></shape>"
            "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"5\"/>"
            "<translate z=\"6\"/></transform></shape>");
    };
    auto render_with = [&](const std::string& in_image, uint32_t spp, bool stop_first) {
        auto scene = load_scene_string(xml(in_image));
        std::atomic<bool> stop{stop_first};
        RenderOptions opt;
        opt.spp = spp;
        opt.stop = &stop;
        return render(*scene, opt);
    };
    const RenderStats in_image = render_with("true", 8, false);
    const RenderStats separate = render_with("false", 8, false);
    EXPECT_EQ(in_image.spp_done, 8u);
    EXPECT_EQ(separate.spp_done, 8u);
    EXPECT_EQ(in_image.pilot_seconds, 0.0);
    EXPECT_EQ(in_image.pilot_image_spp, 8u);
    EXPECT_GT(separate.pilot_seconds, 0.0);
    EXPECT_EQ(separate.pilot_image_spp, 0u);
    // Both trace 8 samples' paths per pixel for the image; the separate pilot as many again.
    const double ratio = double(separate.rays) / double(in_image.rays);
    EXPECT_GT(ratio, 1.8);
    EXPECT_LT(ratio, 2.2);
    // More samples than the pilot's: the passes after it take the rest.
    const RenderStats longer = render_with("true", 20, false);
    EXPECT_EQ(longer.spp_done, 20u);
    EXPECT_NEAR(double(longer.rays) / double(in_image.rays), 2.5, 0.25);
    // Stopped before it starts: not a sample.
    const RenderStats stopped = render_with("true", 20, true);
    EXPECT_TRUE(stopped.interrupted);
    EXPECT_EQ(stopped.spp_done, 0u);
}

TEST(Render, StopFlagTakesEffectWithinAPass) {
    auto scene = load_scene_string(femto::test::scene_xml(
        "<sensor type=\"perspective\"><film type=\"hdrfilm\"><integer name=\"width\" value=\"8\"/>"
        "<integer name=\"height\" value=\"8\"/><rfilter type=\"box\"/></film></sensor>"
        "<shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"0\" z=\"4\"/>"
        "<emitter type=\"area\"><float name=\"radiance\" value=\"2\"/></emitter></shape>"));
    // Set before the render: not a single sample (a pass no longer has to finish; cli.sigint_*
    // check a stop in the middle of a pass and the outputs it leaves).
    std::atomic<bool> stop{true};
    RenderOptions opt;
    opt.spp = 64;
    opt.stop = &stop;
    const RenderStats stopped = render(*scene, opt);
    EXPECT_TRUE(stopped.interrupted);
    EXPECT_EQ(stopped.spp_done, 0u);
    stop = false;
    const RenderStats full = render(*scene, opt);
    EXPECT_FALSE(full.interrupted);
    EXPECT_EQ(full.spp_done, 64u);
    const auto img = scene->sensor().film().steady_image();
    EXPECT_NEAR(img[3 * (4 * 8 + 4)], 2.f, 1e-5f);
}

// hdrfilm refuses a camera sample with a NaN, infinite or negative contribution as the
// time-resolved films do (test_viz.cpp, StreakFilm.RejectsBadSamplesAsTheTransientFilm): the
// image is that of the good samples alone and each bad contribution is counted by its kind.
TEST(HdrFilm, RejectsBadSamplesAndCountsThem) {
    auto scene = load_scene_string(test::scene_xml(test::kRect));
    Film& film = scene->sensor().film();
    ContributionList good, nan, inf, negative;
    good.add(Color(1.f), 0.0);
    nan.add(Color(1.f), 0.0);
    nan.add(Color(std::nanf(""), 0.f, 0.f), 0.0);
    inf.add(Color(0.f, INFINITY, 0.f), 0.0);
    negative.add(Color(1.f, -1e-6f, 1.f), 0.0);
    negative.add(Color(0.f, 0.f, -2.f), 0.0);
    auto block = film.make_block(0, 0, 8, 8);
    for (const ContributionList* sample : {&nan, &good, &inf, &negative})
        block->put(Vec2{2.5f, 3.5f}, *sample);
    film.merge(*block);
    const RejectedContributions r = film.rejected();
    EXPECT_EQ(r.nan, 1u);
    EXPECT_EQ(r.infinite, 1u);
    EXPECT_EQ(r.negative, 2u);
    const std::vector<float> img = film.steady_image();
    for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(img[(3 * 8 + 2) * 3 + size_t(c)], 1.f);
}
