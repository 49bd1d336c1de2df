// The renderer: passes over image tiles, run in parallel with TBB.
//
// Determinism: a camera sample's random numbers depend only on (seed, pixel, sample index),
// and tiles are merged in four phases of a 2x2 colouring, so that tiles merged at the same
// time never overlap (their filter borders are narrower than a tile) and every pixel receives
// its neighbours' splats in the same order whatever the thread count or schedule.
#include <fmt/format.h>
#include <pmmintrin.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <unistd.h>
#include <xmmintrin.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <thread>

#include "femto/host.h"
#include "femto/integrator.h"
#include "femto/sensor.h"

namespace femto {

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kTileSize = 32;

struct Tile {
    int x0, y0, w, h;
};

std::string format_duration(double s) {
    if (!std::isfinite(s) || s < 0) return "--:--";
    const long t = long(s + 0.5);
    if (t >= 3600) return fmt::format("{}:{:02}:{:02}", t / 3600, (t / 60) % 60, t % 60);
    return fmt::format("{:02}:{:02}", t / 60, t % 60);
}

class Progress {
public:
    Progress(bool enabled, uint64_t total)
        : enabled_(enabled), total_(total), start_(Clock::now()) {}
    void advance(uint64_t n) {
        const uint64_t done = done_.fetch_add(n) + n;
        if (!enabled_) return;
        std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
        if (!lock.owns_lock()) return;
        const auto now = Clock::now();
        if (done < total_ && now - last_print_ < std::chrono::milliseconds(250)) return;
        last_print_ = now;
        print(done, now);
    }
    void finish() {
        if (!enabled_) return;
        std::lock_guard<std::mutex> lock(mutex_);
        print(done_.load(), Clock::now());
        std::fputc('\n', stderr);
    }

private:
    void print(uint64_t done, Clock::time_point now) {
        const double elapsed = std::chrono::duration<double>(now - start_).count();
        const double frac = total_ ? double(done) / double(total_) : 1.0;
        const double rate = elapsed > 0 ? double(done) / elapsed : 0.0;
        const double eta = rate > 0 ? double(total_ - done) / rate : NAN;
        constexpr int kBar = 30;
        const int filled = int(frac * kBar);
        std::fprintf(stderr, "\rRendering [%s%s] %5.1f%% | %s elapsed | ETA %s | %.2f M samples/s ",
                     std::string(filled, '#').c_str(), std::string(kBar - filled, ' ').c_str(),
                     100.0 * frac, format_duration(elapsed).c_str(), format_duration(eta).c_str(),
                     rate * 1e-6);
        std::fflush(stderr);
    }

    bool enabled_;
    uint64_t total_;
    std::atomic<uint64_t> done_{0};
    Clock::time_point start_, last_print_{};
    std::mutex mutex_;
};

void enable_flush_to_zero() {
    // Embree asks for FTZ/DAZ in every thread that traces rays.
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}

// The tile side: 32 pixels, or less when the film's blocks are as dense as the film (a
// transient cube) and a 32-pixel block (with its filter border) would exceed 1/32 of the film,
// so that the blocks of a few threads add little to the film's memory. It depends on the film
// alone, never on the thread count: renders stay bit-identical across thread counts. A tile is
// at least twice the filter's radius (the 2x2 colouring needs borders narrower than a tile).
int tile_size_for(const Film& film) {
    const int border = film.filter_border();
    const int smallest = std::max(4, int(std::ceil(2 * film.rfilter().radius())));
    if (film.block_bytes_per_pixel() == 0) return kTileSize;
    const int64_t budget = int64_t(film.width()) * film.height() / 32;
    int size = kTileSize;
    while (size / 2 >= smallest && int64_t(size + 2 * border) * (size + 2 * border) > budget)
        size /= 2;
    return size;
}

// Tiles grouped by colour (tx % 2, ty % 2): tiles of one colour never overlap, filter borders
// included, so they merge at the same time without locks.
std::array<std::vector<Tile>, 4> tiles_by_colour(int W, int H, int tile) {
    std::array<std::vector<Tile>, 4> by_colour;
    for (int ty = 0; ty * tile < H; ++ty)
        for (int tx = 0; tx * tile < W; ++tx)
            by_colour[size_t((ty % 2) * 2 + (tx % 2))].push_back({tx * tile, ty * tile,
                                                                  std::min(tile, W - tx * tile),
                                                                  std::min(tile, H - ty * tile)});
    return by_colour;
}

// Samples [s0, s1) of every pixel of `tile`: each camera sample's numbers come from (seed,
// pixel, sample index) alone. The tile's block is merged into the film at the end. A stop
// request ends the tile early (Ctrl-C takes effect within a few samples' work, whatever the
// pass size): the samples taken are merged, so the pixels keep valid, if unequal, estimates.
// Returns the number of camera samples taken.
uint64_t render_tile(const Scene& scene, const Tile& tile, uint64_t seed, uint32_t s0, uint32_t s1,
                     Sampler& sampler, ContributionList& list, const std::atomic<bool>* stop) {
    const Sensor& sensor = scene.sensor();
    Film& film = sensor.film();
    const Integrator& integrator = scene.integrator();
    auto block = film.make_block(tile.x0, tile.y0, tile.w, tile.h);
    uint64_t taken = 0;
    for (int y = tile.y0; y < tile.y0 + tile.h; ++y) {
        if (!film.row_active(y)) continue;
        for (int x = tile.x0; x < tile.x0 + tile.w; ++x) {
            const uint64_t pixel = uint64_t(y) * uint64_t(film.width()) + uint64_t(x);
            for (uint32_t s = s0; s < s1; ++s) {
                if (stop && stop->load(std::memory_order_relaxed)) {
                    film.merge(*block);
                    return taken;
                }
                ++taken;
                sampler.start(seed, pixel, s);
                const Vec2 jitter = sampler.next_2d();
                const Vec2 pos{float(x) + jitter.x, float(y) + jitter.y};
                const Ray ray = sensor.sample_ray(pos, sampler.next_2d());
                list.clear();
                list.set_sample_index(s);
                integrator.sample(scene, sampler, ray, list);
                block->put(pos, list);
            }
        }
    }
    film.merge(*block);
    return taken;
}

}  // namespace

RenderStats render(Scene& scene, const RenderOptions& options) {
    const Sensor& sensor = scene.sensor();
    Film& film = sensor.film();
    const Sampler& prototype = sensor.sampler();
    const uint32_t spp = options.spp ? options.spp : prototype.sample_count();
    if (spp == 0) throw SceneError("the number of samples per pixel must be positive");
    if (options.threads < 0) throw SceneError("the thread count must be positive (0 = all cores)");

    std::unique_ptr<tbb::global_control> limit;
    if (options.threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      size_t(options.threads));
    enable_flush_to_zero();
    scene.integrator().preprocess(scene);

    const int W = film.width(), H = film.height();
    const auto by_colour = tiles_by_colour(W, H, tile_size_for(film));
    if (film.rfilter().radius() > kTileSize / 2)
        throw SceneError(
            film.rfilter().location(),
            fmt::format("the reconstruction filter's radius ({} px) is larger than femto "
                        "supports ({} px)",
                        film.rfilter().radius(), kTileSize / 2));

    // Passes: small enough for Ctrl-C and progressive films, large enough to amortise merges.
    // At most ~4M camera samples per pass keeps Ctrl-C responsive at any spp.
    const uint64_t pixels = uint64_t(W) * uint64_t(H);
    constexpr uint64_t kMaxPassSamples = uint64_t(1) << 22;
    const uint32_t pass_spp = uint32_t(
        std::max<uint64_t>(1, std::min<uint64_t>((spp + 15) / 16, kMaxPassSamples / pixels)));
    const uint32_t pilot_spp = film.pilot_samples();
    Progress progress(options.progress, pixels * (uint64_t(spp) + pilot_spp));
    tbb::enumerable_thread_specific<std::unique_ptr<Sampler>> samplers(
        [&] { return prototype.clone(); });
    tbb::enumerable_thread_specific<ContributionList> lists;

    // Samples [s0, s1) of every pixel, tiles of one colour at a time; returns the share of
    // the pass's samples taken (1 unless stopped).
    uint64_t active_pixels = 0;
    for (int y = 0; y < H; ++y) active_pixels += film.row_active(y) ? uint64_t(W) : 0;
    auto run_pass = [&](uint64_t seed, uint32_t s0, uint32_t s1) {
        std::atomic<uint64_t> taken{0};
        for (const auto& tiles : by_colour) {
            tbb::parallel_for(size_t(0), tiles.size(), [&](size_t t) {
                enable_flush_to_zero();
                taken += render_tile(scene, tiles[t], seed, s0, s1, *samplers.local(),
                                     lists.local(), options.stop);
                progress.advance(uint64_t(tiles[t].w) * uint64_t(tiles[t].h) * (s1 - s0));
            });
        }
        return double(taken.load()) / double(std::max<uint64_t>(1, active_pixels * (s1 - s0)));
    };

    const uint64_t rays_before = scene.rays_traced();
    const auto start = Clock::now();
    RenderStats stats;
    stats.spp_requested = spp;
    auto stopped = [&] { return options.stop && options.stop->load(); };
    if (pilot_spp > 0) {
        // The pilot's random streams are independent of the image's (another seed).
        film.begin_pilot();
        scene.refresh_time_window();
        run_pass(options.seed ^ 0x9E3779B97F4A7C15ull, 0, pilot_spp);
        film.end_pilot();  // a stopped pilot still leaves the film a usable (rougher) estimate
    }
    uint32_t pass = 0;
    for (uint32_t s0 = 0; s0 < spp && !stopped(); s0 += pass_spp, ++pass) {
        const uint32_t s1 = std::min(spp, s0 + pass_spp);
        film.start_pass(pass);
        scene.refresh_time_window();
        const double share = run_pass(options.seed, s0, s1);
        // Stopped within the pass, some pixels have s1 samples and others s0: the mean.
        stats.spp_done = share >= 1 ? s1 : s0 + uint32_t(double(s1 - s0) * share);
    }
    stats.interrupted = stats.spp_done < spp;  // only a stop request ends the loop early
    progress.finish();
    stats.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    stats.rays = scene.rays_traced() - rays_before;
    stats.camera_samples = pixels * stats.spp_done;
    return stats;
}

RenderInfo make_render_info(const Scene& scene, const RenderOptions& options,
                            const RenderStats& stats) {
    RenderInfo info;
    info.scene_file = options.scene_file;
    info.integrator = scene.integrator().type_name();
    info.femto_version = version();
    info.seed = options.seed;
    info.samples_per_pixel = stats.spp_done;
    info.samples_requested = stats.spp_requested;
    info.render_seconds = stats.seconds;
    info.interrupted = stats.interrupted;
    return info;
}

}  // namespace femto
