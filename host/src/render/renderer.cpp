// The renderer: passes over image tiles, run in parallel with TBB.
//
// Determinism: a camera sample's random numbers depend only on (seed, pixel, sample index),
// and tiles are ordered by a 2x2 colouring: tiles of one colour never overlap (their filter
// borders are narrower than a tile), and a tile's block merges after the overlapping blocks of
// earlier colours (TileSchedule; splats after each colour's tiles), so every pixel receives its
// blocks and splats in the same order whatever the thread count or schedule.
#include <fmt/format.h>
#include <pmmintrin.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>
#include <xmmintrin.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "femto/bsdf.h"
#include "femto/host.h"
#include "femto/integrator.h"
#include "femto/log.h"
#include "femto/scene.h"
#include "femto/sensor.h"
#include "render/tiles.h"

namespace femto {

// The tile side: 32 pixels, or less, for two reasons. A pass renders its tiles in parallel, so
// the tiles are all the work its threads can share: the side halves (down to kSmallestTile)
// until at least kMinTiles tiles meet rows the film records (a streak film records few), so
// that a small film still keeps many cores busy (in 32-pixel tiles a 32x32 film is one tile,
// rendered by one thread however many there are). And when the film's blocks are as dense as
// the film (a transient cube), it halves further while a block (with its filter border) would
// exceed 1/32 of the film, so that the blocks of a few threads add little to the film's
// memory. It depends on the film alone, never on the thread count: renders stay bit-identical
// across thread counts. A tile is at least twice the filter's radius, so at least twice its
// border (the 2x2 colouring: tiles of one colour lie a tile apart and must not overlap).
int detail::tile_size_for(const Film& film) {
    constexpr int64_t kMinTiles = 64;  // 2 or more a thread up to 32 threads
    constexpr int kSmallestTile = 8;   // smaller ones cost more per tile than they balance
    const int border = film.filter_border();
    const int smallest = std::max(4, int(std::ceil(2 * film.rfilter().radius())));
    const int64_t W = film.width(), H = film.height();
    auto tiles = [&](int size) {  // that meet a row the film records
        int64_t rows = 0;
        for (int64_t y0 = 0; y0 < H; y0 += size)
            for (int64_t y = y0; y < std::min(H, y0 + size); ++y)
                if (film.row_active(int(y))) {
                    ++rows;
                    break;
                }
        return rows * ((W + size - 1) / size);
    };
    int size = Film::kMaxTileSize;
    while (size / 2 >= std::max(kSmallestTile, smallest) && tiles(size) < kMinTiles) size /= 2;
    if (film.block_bytes_per_pixel() == 0) return size;
    const int64_t budget = W * H / 32;
    while (size / 2 >= smallest && int64_t(size + 2 * border) * (size + 2 * border) > budget)
        size /= 2;
    return size;
}

namespace {

using Clock = std::chrono::steady_clock;

constexpr int kTileSize = Film::kMaxTileSize;
constexpr uint64_t kMaxKeptPilotSamples = uint64_t(1) << 16;
constexpr uint64_t kMinPassSpp = 8;  // samples per pixel of a pass, where there are enough

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
    // `lines`: one line per round of passes (round_done()) instead of the redrawn bar.
    Progress(bool enabled, uint64_t total, bool lines)
        : enabled_(enabled), lines_(lines), total_(total), start_(Clock::now()) {}
    void advance(uint64_t n) {
        const uint64_t done = done_.fetch_add(n) + n;
        if (!enabled_ || lines_) return;
        std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
        if (!lock.owns_lock()) return;
        const auto now = Clock::now();
        if (done < total_ && now - last_print_ < std::chrono::milliseconds(250)) return;
        last_print_ = now;
        print(done, now);
    }
    // Passes [0, passes_done) of `passes` are done in every process.
    // At most a line per second (and always the last), so that short renders stay brief.
    void round_done(uint64_t passes_done, uint64_t passes) {
        if (!enabled_ || !lines_) return;
        const auto now = Clock::now();
        if (passes_done < passes && now - last_print_ < std::chrono::seconds(1)) return;
        last_print_ = now;
        const double elapsed = std::chrono::duration<double>(now - start_).count();
        const double frac = double(passes_done) / double(std::max<uint64_t>(1, passes));
        const double eta = frac > 0 ? elapsed * (1 - frac) / frac : NAN;
        std::fprintf(stderr, "femto: %llu of %llu passes done (%.1f%%) | %s elapsed | ETA %s\n",
                     (unsigned long long)passes_done, (unsigned long long)passes, 100.0 * frac,
                     format_duration(elapsed).c_str(), format_duration(eta).c_str());
        std::fflush(stderr);
    }
    void finish() {
        if (!enabled_ || lines_) return;
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

    bool enabled_, lines_;
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

// The tiles of a camera pass without splats, rendered in one parallel loop with no barrier
// between the colours. Workers take the tiles in colour order from a shared counter, and a
// tile's block merges once the tiles of earlier colours whose filter borders overlap it have
// merged: every pixel receives its blocks in the order the four colour phases give, so images
// stay bit-identical at any thread count, while a worker done with the last tiles of a colour
// goes on to the next colour instead of waiting for the slowest tile (with 16 tiles per colour
// and 32 threads, half of them idled in every phase). A worker waits only for tiles taken
// before its own, which other workers are rendering, so the loop cannot deadlock; memory holds
// one block per worker, as the phases did.
class TileSchedule {
public:
    TileSchedule(const std::array<std::vector<Tile>, 4>& by_colour, int W, int H, int tile,
                 int border) {
        const int columns = (W + tile - 1) / tile, rows = (H + tile - 1) / tile;
        std::vector<size_t> at(size_t(columns) * size_t(rows));  // grid cell -> tiles_ index
        std::vector<int> colour;
        for (int c = 0; c < 4; ++c)
            for (const Tile& t : by_colour[size_t(c)]) {
                at[size_t(t.y0 / tile) * size_t(columns) + size_t(t.x0 / tile)] = tiles_.size();
                tiles_.push_back(t);
                colour.push_back(c);
            }
        predecessors_.resize(tiles_.size());
        for (size_t i = 0; i < tiles_.size() && border > 0; ++i) {
            // Borders are narrower than a tile: only the 8 adjacent tiles overlap this one.
            const int tx = tiles_[i].x0 / tile, ty = tiles_[i].y0 / tile;
            for (int y = std::max(0, ty - 1); y <= std::min(rows - 1, ty + 1); ++y)
                for (int x = std::max(0, tx - 1); x <= std::min(columns - 1, tx + 1); ++x) {
                    const size_t j = at[size_t(y) * size_t(columns) + size_t(x)];
                    if (colour[j] < colour[i]) predecessors_[i].push_back(j);
                }
        }
        merged_ = std::make_unique<std::atomic<bool>[]>(tiles_.size());
    }

    const std::vector<Tile>& tiles() const { return tiles_; }

    /// Runs render(tile) -> std::unique_ptr<FilmBlock> for the tiles [begin, end) and merges
    /// the blocks into `film` in the order above. A pass runs [0, n) at once, or in ranges in
    /// increasing order (a tile's predecessors come before it: those of an earlier range are
    /// merged by then). An exception from a tile ends the loop (every tile taken is still
    /// marked done, so that no worker waits for it) and is rethrown.
    template <typename Render>
    void run(Film& film, Render&& render, size_t begin = 0, size_t end = SIZE_MAX) {
        end = std::min(end, tiles_.size());
        if (begin == 0)  // a new pass
            for (size_t i = 0; i < tiles_.size(); ++i) merged_[i].store(false);
        std::atomic<size_t> next{begin};
        std::atomic<bool> failed{false};
        std::exception_ptr error;
        std::mutex error_mutex;
        const int workers = tbb::this_task_arena::max_concurrency();
        tbb::parallel_for(
            tbb::blocked_range<int>(0, workers, 1),
            [&](const tbb::blocked_range<int>&) {
                for (size_t i; !failed && (i = next.fetch_add(1)) < end;) {
                    try {
                        // Isolated: a nested TBB loop in a plugin (integrator, film, temporal
                        // filter) must not let this thread pick up another worker, whose wait
                        // would then block the tile below it on the same stack.
                        tbb::this_task_arena::isolate([&] {
                            const std::unique_ptr<FilmBlock> block = render(tiles_[i]);
                            for (const size_t p : predecessors_[i]) merged_[p].wait(false);
                            film.merge(*block);
                        });
                    } catch (...) {
                        std::lock_guard<std::mutex> lock(error_mutex);
                        if (!error) error = std::current_exception();
                        failed = true;
                    }
                    merged_[i].store(true);
                    merged_[i].notify_all();
                }
            },
            tbb::simple_partitioner());
        if (error) std::rethrow_exception(error);
    }

private:
    std::vector<Tile> tiles_;
    std::vector<std::vector<size_t>> predecessors_;  // overlapping tiles of earlier colours
    std::unique_ptr<std::atomic<bool>[]> merged_;
};

// A camera sample's film position in pixel (x, y) for a jitter in [0, 1)^2: inside [x, x + 1) x
// [y, y + 1) even where x + jitter rounds up to x + 1 in float (a jitter within 2^-24 x of 1),
// so that the film gives it to the pixel it was taken for (a 1-spp pixel would stay black).
// The float below x + 1 (>= 1, so positive and normal, and exact: films are at most 2^16
// pixels across) is the one whose bits are one less: what std::nextafter returns, without its
// call into libm (two per camera sample).
Vec2 pixel_position(int x, int y, Vec2 jitter) {
    auto below_next = [](int i) {
        return std::bit_cast<float>(std::bit_cast<uint32_t>(float(i) + 1.f) - 1u);
    };
    return {std::min(float(x) + jitter.x, below_next(x)),
            std::min(float(y) + jitter.y, below_next(y))};
}

// Adaptive sampling (thesis ch. 3, Fig. 3.15): how many camera samples each pixel takes, spp_p =
// max(1, ceil(s x spp)) with s the share the material its centre ray meets first asks for
// (Bsdf::pixel_sample_share()). Empty: every pixel takes spp.
struct PixelCounts {
    std::vector<uint32_t> count;  // per pixel, row-major; empty when not adaptive

    uint32_t end(uint64_t pixel, uint32_t s1) const {
        return count.empty() ? s1 : std::min(s1, count[pixel]);
    }
    // Samples [s0, s1) of every pixel take (with counts).
    uint64_t taken(uint32_t s0, uint32_t s1) const {
        uint64_t n = 0;
        for (const uint32_t c : count) n += std::min(c, s1) > s0 ? std::min(c, s1) - s0 : 0;
        return n;
    }
    // Samples [s0, s1) of the pixels of `tile` take, in every row or only in the film's
    // active ones.
    uint64_t in(const Tile& tile, int width, uint32_t s0, uint32_t s1, const Film* active) const {
        uint64_t n = 0;
        for (int y = tile.y0; y < tile.y0 + tile.h; ++y) {
            if (active && !active->row_active(y)) continue;
            if (count.empty()) {
                n += uint64_t(tile.w) * (s1 - s0);
                continue;
            }
            for (int x = tile.x0; x < tile.x0 + tile.w; ++x) {
                const uint32_t e = end(uint64_t(y) * uint64_t(width) + uint64_t(x), s1);
                n += e > s0 ? e - s0 : 0;
            }
        }
        return n;
    }
};

// Whether some material of the scene answers true to `question` (Bsdf::adapts_sampling,
// Bsdf::uses_footprint).
bool any_material(const Scene& scene, bool (Bsdf::*question)() const) {
    for (const auto& shape : scene.shapes())
        if (shape->bsdf() && (shape->bsdf()->*question)()) return true;
    return false;
}

// One ray through each pixel's centre (with its differential, for the footprint) finds the
// material that sets the pixel's count. Integrators that splat put light on other pixels than
// their camera sample's, which per-pixel counts would weigh wrongly: they take spp everywhere.
PixelCounts pixel_counts(const Scene& scene, uint32_t spp, bool splatting) {
    PixelCounts counts;
    if (!any_material(scene, &Bsdf::adapts_sampling)) return counts;
    if (splatting) {
        log_warning(
            fmt::format("adaptive sampling is off: {} splats light onto other pixels "
                        "than its camera samples', so every pixel takes {} samples",
                        scene.integrator().type_name(), spp));
        return counts;
    }
    const Sensor& sensor = scene.sensor();
    const int W = sensor.film().width(), H = sensor.film().height();
    counts.count.assign(size_t(W) * size_t(H), spp);
    tbb::parallel_for(0, H, [&](int y) {
        for (int x = 0; x < W; ++x) {
            const Vec2 pos{float(x) + 0.5f, float(y) + 0.5f}, aperture{0.5f, 0.5f};
            Ray ray = sensor.sample_ray(pos, aperture);
            RayDifferential differential;
            if (sensor.sample_differential(pos, aperture, differential))
                ray.differential = &differential;
            Hit hit;
            if (!scene.intersect(ray, hit) || !hit.shape->bsdf()) continue;
            const Bsdf& bsdf = *hit.shape->bsdf();
            if (!bsdf.adapts_sampling()) continue;
            const float share = bsdf.pixel_sample_share(hit);
            const double s = std::isfinite(share) ? std::clamp(double(share), 0.0, 1.0) : 1.0;
            counts.count[size_t(y) * size_t(W) + size_t(x)] =
                std::max<uint32_t>(1, uint32_t(std::min(double(spp), std::ceil(s * spp))));
        }
    });
    return counts;
}

// Samples [s0, s1) of every pixel of `tile`: each camera sample's numbers come from (seed,
// pixel, sample index) alone. A stop request ends the tile early (Ctrl-C takes effect within a
// few samples' work, whatever the pass size): the samples taken are in the block, so the pixels
// keep valid, if unequal, estimates.
// With adaptive sampling a pixel stops at its own count. Camera rays carry differentials when
// `differentials` (some material reads the footprint). Returns the number of camera samples
// taken and the tile's block of the film, which the caller merges (a stopped tile's too).
struct RenderedTile {
    uint64_t taken = 0;  // camera samples
    std::unique_ptr<FilmBlock> block;
};
RenderedTile render_tile(const Scene& scene, const Tile& tile, uint64_t seed, uint32_t s0,
                         uint32_t s1, const PixelCounts& counts, bool differentials,
                         Sampler& sampler, ContributionList& list, SplatList* splats,
                         const std::atomic<bool>* stop) {
    const Sensor& sensor = scene.sensor();
    Film& film = sensor.film();
    const Integrator& integrator = scene.integrator();
    auto block = film.make_block(tile.x0, tile.y0, tile.w, tile.h);
    const float ray_weight = sensor.ray_weight();
    const size_t aov_count = integrator.aov_names().size();
    list.set_splat_list(splats);
    uint64_t taken = 0;
    for (int y = tile.y0; y < tile.y0 + tile.h; ++y) {
        if (!film.row_active(y)) continue;
        for (int x = tile.x0; x < tile.x0 + tile.w; ++x) {
            const uint64_t pixel = uint64_t(y) * uint64_t(film.width()) + uint64_t(x);
            const uint32_t end = counts.end(pixel, s1);
            for (uint32_t s = s0; s < end; ++s) {
                if (stop && stop->load(std::memory_order_relaxed)) return {taken, std::move(block)};
                ++taken;
                sampler.start(seed, pixel, s);
                const Vec2 pos = pixel_position(x, y, sampler.next_2d());
                const Vec2 aperture = sampler.next_2d();
                Ray ray = sensor.sample_ray(pos, aperture);
                // The neighbouring pixels' rays, for the first hit's footprint (materials that
                // prefilter); the ray points to it only for this sample.
                RayDifferential differential;
                if (differentials && sensor.sample_differential(pos, aperture, differential)) {
                    differential.to_pixel_centre = {float(x) + 0.5f - pos.x,
                                                    float(y) + 0.5f - pos.y};
                    ray.differential = &differential;
                }
                list.clear();
                list.reset_aovs(aov_count);
                list.set_sample_index(s);
                list.set_film_position(pos);
                if (splats) splats->set_sample_index(s);
                integrator.sample(scene, sampler, ray, list);
                if (ray_weight != 1.f) list.scale(ray_weight);
                block->put(pos, list);
            }
        }
    }
    return {taken, std::move(block)};
}

// The tiles of the film in a grid (tile index = row * columns + column), each with its colour
// group, for merging splats: splats land anywhere, so they are bucketed by the tile that holds
// their film position and merged tile by tile in the same 2x2 colouring as camera samples.
class SplatMerger {
public:
    SplatMerger(int W, int H, int tile)
        : W_(W), H_(H), tile_(tile), columns_((W + tile - 1) / tile) {
        by_colour_ = tiles_by_colour(W, H, tile);
        rows_ = (H + tile - 1) / tile;
    }

    // Merges the splats of `lists` into the film, in list order and, within a list, in the
    // order they were made: every pixel receives them in the same order whatever the thread
    // count. Splats outside the film are dropped.
    void merge(Film& film, const std::vector<const SplatList*>& lists) {
        // The splats bucketed by tile, in list order within a tile. The lists are cut into at
        // most kBucketRuns runs of consecutive lists (a number that does not depend on the
        // thread count, so neither does the order), which count their splats per tile and then
        // place them at the offsets their counts give, the runs in parallel: a serial pass over
        // a pass's splats held every other thread up, and a count table per list would grow as
        // lists x tiles (with a list per tile, 2 GB for a 4096x4096 hdrfilm).
        const size_t tiles = size_t(columns_) * size_t(rows_), n = lists.size();
        const size_t runs = std::min(n, kBucketRuns);
        auto splats_of_run = [&](size_t r, auto&& visit) {  // visit(tile, splat), in order
            for (size_t l = r * n / runs; l < (r + 1) * n / runs; ++l)
                for (const Splat& s : lists[l]->items())
                    if (const int64_t t = tile_of(s.pos); t >= 0) visit(size_t(t), s);
        };
        next_.assign(runs * tiles, 0);  // [run][tile]: the count, then the next slot
        tbb::parallel_for(size_t(0), runs, [&](size_t r) {
            size_t* count = &next_[r * tiles];
            splats_of_run(r, [&](size_t t, const Splat&) { ++count[t]; });
        });
        start_.assign(tiles + 1, 0);
        size_t placed = 0;
        for (size_t t = 0; t < tiles; ++t) {
            start_[t] = placed;
            for (size_t r = 0; r < runs; ++r) placed += std::exchange(next_[r * tiles + t], placed);
        }
        start_[tiles] = placed;
        order_.resize(placed);
        tbb::parallel_for(size_t(0), runs, [&](size_t r) {
            size_t* next = &next_[r * tiles];
            splats_of_run(r, [&](size_t t, const Splat& s) { order_[next[t]++] = &s; });
        });
        for (const auto& group : by_colour_)
            tbb::parallel_for(size_t(0), group.size(), [&](size_t i) {
                const Tile& tile = group[i];
                const size_t t =
                    size_t(tile.y0 / tile_) * size_t(columns_) + size_t(tile.x0 / tile_);
                if (start_[t] == start_[t + 1]) return;
                auto block = film.make_block(tile.x0, tile.y0, tile.w, tile.h);
                ContributionList one;
                one.set_is_splat(true);
                const size_t end = start_[t + 1];
                for (size_t k = start_[t]; k < end; ++k) {
                    // The splats lie scattered over the tiles' lists that other threads wrote:
                    // each was a cache miss (most of the merge's time at 2 threads).
                    if (k + kPrefetchAhead < end) __builtin_prefetch(order_[k + kPrefetchAhead]);
                    const Splat& s = *order_[k];
                    one.clear();
                    one.add(s.radiance, s.time);
                    one.set_sensor_distance(s.sensor_distance);
                    one.set_sample_index(s.sample_index);
                    block->put(s.pos, one);
                }
                film.merge(*block);
            });
    }

private:
    static constexpr size_t kPrefetchAhead = 16;  // splats
    static constexpr size_t kBucketRuns = 16;     // lists' runs bucketed in parallel

    int64_t tile_of(Vec2 pos) const {
        if (!(pos.x >= 0 && pos.x < float(W_) && pos.y >= 0 && pos.y < float(H_))) return -1;
        const int x = std::min(W_ - 1, int(pos.x)), y = std::min(H_ - 1, int(pos.y));
        return int64_t(y / tile_) * columns_ + x / tile_;
    }

    int W_, H_, tile_, columns_, rows_ = 0;
    std::array<std::vector<Tile>, 4> by_colour_;
    std::vector<size_t> start_, next_;
    std::vector<const Splat*> order_;
};

// Light paths [first, last) of a pass that starts at sample index s0: path k is sample
// s0 + k / pixels of "pixel" k % pixels, so that its random numbers depend on (seed, k) alone.
// Returns the number of paths traced (fewer when stopped).
uint64_t trace_light_paths(const Scene& scene, uint64_t seed, uint32_t s0, uint64_t pixels,
                           uint64_t first, uint64_t last, Sampler& sampler, SplatList& splats,
                           const std::atomic<bool>* stop) {
    const Integrator& integrator = scene.integrator();
    uint64_t taken = 0;
    for (uint64_t k = first; k < last; ++k) {
        if (stop && stop->load(std::memory_order_relaxed)) break;
        const uint32_t s = s0 + uint32_t(k / pixels);
        sampler.start(seed, k % pixels, s);
        splats.set_sample_index(s);
        integrator.sample_light(scene, sampler, splats);
        ++taken;
    }
    return taken;
}

// How a render's samples split into passes, and the temporal filter's pilot.
struct PassPlan {
    uint32_t spp = 0;             // samples per pixel of the whole image
    uint32_t pilot_spp = 0;       // the temporal filter's pilot (0: none)
    bool pilot_in_image = false;  // the pilot is the image's first samples
    uint32_t first_spp = 0;       // samples before the passes (the pilot, when in the image)
    uint32_t pass_spp = 1;
    uint32_t passes = 0;

    // Samples [s0, s1) of every pixel that pass `pass` takes.
    std::pair<uint32_t, uint32_t> range(uint32_t pass) const {
        const uint32_t s0 = uint32_t(first_spp + uint64_t(pass) * pass_spp);
        return {s0, uint32_t(std::min<uint64_t>(spp, uint64_t(s0) + pass_spp))};
    }
};

// Passes: small enough for Ctrl-C and progressive films, large enough to amortise merges.
// At most ~4M camera samples per pass keeps Ctrl-C responsive at any spp; camera
// integrators that splat keep a pass's splats in memory until its end, so theirs take at
// most 65,536 (BDPT's splats of a pass: ~10 MB on the Cornell box, which a larger pass
// would merge from beyond the cache: 256x256 at 4x this ran 7-10 % slower), and on films
// of more pixels than that, one sample per pixel, merged in groups of tiles. A
// distributed render runs pass p in process p % ranks, with about 16 passes per process.
// A pass gives each pixel at least kMinPassSpp samples where every process still gets a
// pass: a time-resolved film's merge updates a cache line of its cube per (pixel, bin) it
// received, and a pixel's samples in one pass share them (the Cornell box: 2.09 lines per
// sample at 2 spp per pass, 1.63 at 8; bench/README.md).
// A temporal filter's pilot: the image's first samples when the film can keep them (not
// for integrators that splat or fix their samples per pass), else a pass of its own.
// A tile keeps its pilot samples (40 bytes and 32 per contribution: ~230 bytes at 6
// contributions) until its pilot is done: at most kMaxKeptPilotSamples (a 32x32 tile of
// 64 spp, the kernel's default; ~15 MiB).
PassPlan plan_passes(const Film& film, const Integrator& integrator, uint32_t spp, int tile,
                     uint32_t ranks, bool splatting, bool from_lights) {
    PassPlan plan;
    plan.spp = spp;
    plan.pilot_spp = film.pilot_samples();
    const uint32_t pilot_of_image = std::min(plan.pilot_spp, spp);
    const bool pilot_fits =
        uint64_t(tile) * uint64_t(tile) * pilot_of_image <= kMaxKeptPilotSamples;
    const bool pilot_can_be_image = plan.pilot_spp > 0 && !splatting &&
                                    integrator.samples_per_pass() == 0 && film.pilot_in_image();
    plan.pilot_in_image = pilot_can_be_image && pilot_fits;
    if (pilot_can_be_image && !pilot_fits)
        log_note(SourceLocation{},
                 fmt::format("the temporal filter's pilot of {} spp is too large to keep in the "
                             "image ({}x{} pixel tiles; at most {} samples per tile): it runs as "
                             "a separate pass",
                             pilot_of_image, tile, tile, kMaxKeptPilotSamples));
    plan.first_spp = plan.pilot_in_image ? pilot_of_image : 0;
    const uint64_t pixels = uint64_t(film.width()) * uint64_t(film.height());
    const uint64_t max_pass_samples = uint64_t(1) << (splatting && !from_lights ? 16 : 22);
    const uint64_t passes_wanted = uint64_t(16) * ranks, image_spp = spp - plan.first_spp;
    const uint64_t least_spp = std::min<uint64_t>(kMinPassSpp, image_spp / ranks);
    plan.pass_spp =
        integrator.samples_per_pass() > 0
            ? integrator.samples_per_pass()
            : uint32_t(std::max<uint64_t>(
                  1, std::min<uint64_t>(
                         std::max((image_spp + passes_wanted - 1) / passes_wanted, least_spp),
                         max_pass_samples / pixels)));
    plan.passes = uint32_t((image_spp + plan.pass_spp - 1) / plan.pass_spp);
    return plan;
}

// Runs a render's passes over the film: camera passes tile by tile, or light passes in
// chunks of light paths, with their splats merged in a fixed order.
class PassRunner {
public:
    PassRunner(const Scene& scene, const PixelCounts& counts, bool differentials, bool splatting,
               bool from_lights, const std::atomic<bool>* pass_stop, Progress& progress, int tile)
        : scene_(scene),
          film_(scene.sensor().film()),
          counts_(counts),
          differentials_(differentials),
          splatting_(splatting),
          from_lights_(from_lights),
          pass_stop_(pass_stop),
          progress_(progress),
          samplers_([&scene] { return scene.sensor().sampler().clone(); }),
          merger_(film_.width(), film_.height(), tile),
          schedule_(tiles_by_colour(film_.width(), film_.height(), tile), film_.width(),
                    film_.height(), tile, film_.filter_border()),
          chunk_splats_(from_lights ? kWaveChunks : 0) {}

    // Samples [s0, s1) of every pixel; returns the share of them taken (1 unless stopped).
    double run(uint64_t seed, uint32_t s0, uint32_t s1, bool pilot) {
        return from_lights_ ? light_pass(seed, s0, s1, pilot) : camera_pass(seed, s0, s1, pilot);
    }

private:
    // An integrator that splats: each tile keeps its splats until the last tile of its group is
    // done, and they merge then, in tile order; a group is a run of consecutive tiles of at
    // most kSplatGroupSamples camera samples (or one tile), the whole pass unless the film
    // has more pixels than that. A pixel receives the camera blocks and the splats in an order
    // fixed by the tiles alone, whatever the thread count; memory holds one group's splats;
    // workers wait only at a group's end (a loop per colour, with the splats merged after
    // each, left 2-3 % of 2 threads idle in BDPT and, with 16 tiles per colour, would leave
    // half of 32 idle). Such a pass is not stopped midway (outside a pilot): its splats are
    // normalised by each pixel's own camera samples, so a pass that some tiles had finished
    // and others not would leave tile-sized steps in the image's brightness. A stop takes
    // effect at the pass's end.
    double camera_pass(uint64_t seed, uint32_t s0, uint32_t s1, bool pilot) {
        std::atomic<uint64_t> taken{0};
        const int W = film_.width();
        uint64_t expected = 0;  // in the film's active rows
        for (const Tile& t : schedule_.tiles()) expected += counts_.in(t, W, s0, s1, &film_);
        const std::atomic<bool>* stop = splatting_ && !pilot ? nullptr : pass_stop_;
        auto render_one = [&](const Tile& t, SplatList* splats) {
            enable_flush_to_zero();
            RenderedTile r = render_tile(scene_, t, seed, s0, s1, counts_, differentials_,
                                         *samplers_.local(), lists_.local(), splats, stop);
            taken += r.taken;
            progress_.advance(counts_.in(t, W, s0, s1, nullptr));
            return std::move(r.block);
        };
        const std::vector<Tile>& tiles = schedule_.tiles();
        if (!splatting_) {
            schedule_.run(film_, [&](const Tile& t) { return render_one(t, nullptr); });
        } else {
            for (size_t begin = 0, end; begin < tiles.size(); begin = end) {
                uint64_t samples = counts_.in(tiles[begin], W, s0, s1, nullptr);
                for (end = begin + 1; end < tiles.size(); ++end) {
                    const uint64_t more = counts_.in(tiles[end], W, s0, s1, nullptr);
                    if (samples + more > kSplatGroupSamples) break;
                    samples += more;
                }
                if (group_splats_.size() < end - begin) group_splats_.resize(end - begin);
                schedule_.run(
                    film_,
                    [&](const Tile& t) {
                        SplatList& splats = group_splats_[size_t(&t - tiles.data()) - begin];
                        splats.clear();
                        return render_one(t, &splats);
                    },
                    begin, end);
                std::vector<const SplatList*> in_order;
                for (size_t i = 0; i < end - begin; ++i) in_order.push_back(&group_splats_[i]);
                merger_.merge(film_, in_order);
            }
        }
        // (A pass in which no pixel has samples left, adaptive sampling's, is complete.)
        return expected == 0 ? 1.0 : double(taken.load()) / double(expected);
    }

    // Light paths of samples [s0, s1): pixels x (s1 - s0) of them, in waves of fixed chunks
    // whose splats merge in chunk order after each wave (so memory holds one wave's splats).
    double light_pass(uint64_t seed, uint32_t s0, uint32_t s1, bool pilot) {
        const uint64_t pixels = uint64_t(film_.width()) * uint64_t(film_.height());
        const uint64_t total = pixels * (s1 - s0);
        std::atomic<uint64_t> taken{0};
        for (uint64_t first = 0; first < total; first += kChunk * kWaveChunks) {
            const uint64_t chunks = std::min(kWaveChunks, (total - first + kChunk - 1) / kChunk);
            tbb::parallel_for(uint64_t(0), chunks, [&](uint64_t c) {
                enable_flush_to_zero();
                const uint64_t a = first + c * kChunk, b = std::min(total, a + kChunk);
                chunk_splats_[c].clear();
                taken += trace_light_paths(scene_, seed, s0, pixels, a, b, *samplers_.local(),
                                           chunk_splats_[c], pass_stop_);
                progress_.advance(b - a);
            });
            std::vector<const SplatList*> in_order;
            for (uint64_t c = 0; c < chunks; ++c) in_order.push_back(&chunk_splats_[c]);
            merger_.merge(film_, in_order);
            if (pass_stop_ && pass_stop_->load()) break;
        }
        // Normalise the pass's splats as as many camera samples per pixel would be (a pilot
        // pass only collects arrival times).
        if (!pilot) film_.add_splat_weight(double(taken.load()) / double(pixels));
        return double(taken.load()) / double(std::max<uint64_t>(1, total));
    }

    static constexpr uint64_t kSplatGroupSamples = uint64_t(1) << 16;
    static constexpr uint64_t kChunk = 4096, kWaveChunks = 64;

    const Scene& scene_;
    Film& film_;
    const PixelCounts& counts_;
    const bool differentials_, splatting_, from_lights_;
    const std::atomic<bool>* pass_stop_;
    Progress& progress_;
    tbb::enumerable_thread_specific<std::unique_ptr<Sampler>> samplers_;
    tbb::enumerable_thread_specific<ContributionList> lists_;
    SplatMerger merger_;
    TileSchedule schedule_;
    std::vector<SplatList> group_splats_;
    std::vector<SplatList> chunk_splats_;
};

// Prepares the film for the integrator (splats, AOV channels) and checks what the renderer
// supports. Returns whether the integrator splats.
bool prepare_film(Film& film, const Integrator& integrator) {
    const bool from_lights = integrator.source() == SampleSource::Light;
    const bool splatting = from_lights || integrator.splats();
    if (splatting) film.prepare_splats(from_lights);
    if (const std::vector<std::string> aovs = integrator.aov_names(); !aovs.empty()) {
        if (splatting)
            throw SceneError(integrator.location(),
                             integrator.type_name() +
                                 " declares AOV channels but splats: AOVs are per camera sample");
        film.prepare_aovs(aovs, integrator);
    }
    if (film.rfilter().radius() > kTileSize / 2)
        throw SceneError(
            film.rfilter().location(),
            fmt::format("the reconstruction filter's radius ({} px) is larger than femto "
                        "supports ({} px)",
                        film.rfilter().radius(), kTileSize / 2));
    return splatting;
}

// The camera samples the process's passes take (and its pilot's), for the progress bar.
uint64_t samples_to_take(const PassPlan& plan, const PixelCounts& counts, uint64_t pixels,
                         uint32_t rank, uint32_t ranks) {
    uint64_t samples = 0;
    for (uint32_t pass = rank; pass < plan.passes; pass += ranks) {
        const auto [s0, s1] = plan.range(pass);
        samples += counts.count.empty() ? pixels * (s1 - s0) : counts.taken(s0, s1);
    }
    if (!plan.pilot_in_image) return samples + pixels * plan.pilot_spp;
    return samples +
           (counts.count.empty() ? pixels * plan.first_spp : counts.taken(0, plan.first_spp));
}

// The temporal filter's pilot, before the passes: the image's first samples [0, first_spp),
// which every process traces (each needs the bandwidths) and only rank 0 keeps in its image,
// or a pass of its own whose random streams are independent of the image's (another seed).
void run_pilot(Scene& scene, const RenderOptions& options, const PassPlan& plan, PassRunner& runner,
               uint32_t rank, RenderStats& stats, Clock::time_point start) {
    Film& film = scene.sensor().film();
    if (plan.pilot_in_image) {
        film.begin_pilot(true, rank == 0);
        scene.refresh_time_window();
        scene.integrator().begin_pass(scene,
                                      PassInfo{0, options.seed, 0, plan.first_spp, rank != 0});
        const double share = runner.run(options.seed, 0, plan.first_spp, false);
        film.end_pilot();
        stats.spp_done = share >= 1 ? plan.first_spp : uint32_t(double(plan.first_spp) * share);
        stats.pilot_image_spp = plan.first_spp;
    } else if (plan.pilot_spp > 0) {
        const uint64_t pilot_seed = options.seed ^ 0x9E3779B97F4A7C15ull;
        film.begin_pilot(false, false);
        scene.refresh_time_window();
        scene.integrator().begin_pass(scene, PassInfo{0, pilot_seed, 0, plan.pilot_spp, true});
        runner.run(pilot_seed, 0, plan.pilot_spp, true);
        film.end_pilot();  // a stopped pilot still leaves the film a usable (rougher) estimate
        stats.pilot_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    }
}

// What the render did, once its passes are over.
void finish_stats(const Scene& scene, const PixelCounts& counts, uint64_t pixels,
                  uint64_t rays_before, Clock::time_point start, RenderStats& stats) {
    stats.interrupted = stats.spp_done < stats.spp_requested;  // only a stop ends it early
    stats.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    stats.rays = scene.rays_traced() - rays_before;
    stats.camera_samples = pixels * stats.spp_done;
    if (!counts.count.empty()) {
        stats.camera_samples = 0;
        for (const uint32_t n : counts.count) stats.camera_samples += std::min(n, stats.spp_done);
        stats.adaptive = true;
    }
    stats.rejected = scene.sensor().film().rejected();
    if (const RejectedContributions& r = stats.rejected; r.total() > 0)
        log_warning(
            fmt::format("the film refused {} contributions ({} NaN, {} infinite, {} "
                        "negative) and dropped the samples that carried them",
                        r.total(), r.nan, r.infinite, r.negative));
}

}  // namespace

RenderStats render(Scene& scene, const RenderOptions& options) {
    Film& film = scene.sensor().film();
    const Integrator& integrator = scene.integrator();
    const uint32_t spp = options.spp ? options.spp : scene.sensor().sampler().sample_count();
    if (spp == 0) throw SceneError("the number of samples per pixel must be positive");
    if (options.threads < 0) throw SceneError("the thread count must be positive (0 = all cores)");

    std::unique_ptr<tbb::global_control> limit;
    if (options.threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      size_t(options.threads));
    enable_flush_to_zero();
    scene.integrator().preprocess(scene);
    const bool from_lights = integrator.source() == SampleSource::Light;
    const bool splatting = prepare_film(film, integrator);
    const int tile = detail::tile_size_for(film);
    const uint64_t pixels = uint64_t(film.width()) * uint64_t(film.height());
    const uint32_t ranks = options.group ? uint32_t(options.group->size()) : 1;
    const uint32_t rank = options.group ? uint32_t(options.group->rank()) : 0;
    const PassPlan plan = plan_passes(film, integrator, spp, tile, ranks, splatting, from_lights);
    // In a distributed render, a stop request ends the round of passes (every process
    // finishes its pass, so that the image holds whole passes).
    const std::atomic<bool>* pass_stop = options.group ? nullptr : options.stop;
    const PixelCounts counts = pixel_counts(scene, spp, splatting);
    // Camera rays need their differentials only for materials that read the footprint.
    const bool differentials = any_material(scene, &Bsdf::uses_footprint);
    Progress progress(options.progress, samples_to_take(plan, counts, pixels, rank, ranks),
                      options.progress_lines);
    PassRunner runner(scene, counts, differentials, splatting, from_lights, pass_stop, progress,
                      tile);

    const uint64_t rays_before = scene.rays_traced();
    const auto start = Clock::now();
    RenderStats stats;
    stats.spp_requested = spp;
    auto stopped = [&] { return options.stop && options.stop->load(); };
    run_pilot(scene, options, plan, runner, rank, stats, start);
    for (uint32_t round = 0; uint64_t(round) * ranks < plan.passes; ++round) {
        const uint32_t pass = round * ranks + rank;
        if (pass < plan.passes && !(pass_stop && stopped())) {
            const auto [s0, s1] = plan.range(pass);
            film.start_pass(pass);
            scene.refresh_time_window();
            scene.integrator().begin_pass(scene, PassInfo{pass, options.seed, s0, s1, false});
            const double share = runner.run(options.seed, s0, s1, false);
            // Stopped within the pass, some pixels have s1 samples and others s0: the mean.
            stats.spp_done = share >= 1 ? s1 : s0 + uint32_t(double(s1 - s0) * share);
        }
        const uint64_t passes_done = std::min<uint64_t>(plan.passes, uint64_t(round + 1) * ranks);
        if (options.group) stats.spp_done = plan.range(uint32_t(passes_done - 1)).second;
        progress.round_done(passes_done, plan.passes);
        if (options.group ? options.group->any(stopped()) : stopped()) break;
    }
    progress.finish();
    finish_stats(scene, counts, pixels, rays_before, start, stats);
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
    info.rejected = stats.rejected;
    return info;
}

}  // namespace femto
