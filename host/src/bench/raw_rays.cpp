// Embree's raw ray rate for `femto bench` <raw_rays>. The rays are those a path tracer traces
// most (bounce rays from surfaces, in random directions; shadow rays to lights), generated up
// front so that only Embree's traversal is timed.
#include "bench/raw_rays.h"

#include <embree3/rtcore.h>
#include <pmmintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <xmmintrin.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <thread>

#include "accel/embree_scene.h"
#include "bench/measures.h"
#include "femto/random.h"
#include "femto/shape.h"
#include "femto/warp.h"

namespace femto::bench {

namespace {

using Clock = std::chrono::steady_clock;

// As the renderer's workers do (denormals would slow traversal down).
void enable_flush_to_zero() {
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}

// Shapes picked by area: a cumulative distribution over `shapes`.
struct AreaSampler {
    std::vector<const Shape*> shapes;
    std::vector<float> cdf;
    void finish() {
        double total = 0;
        for (const Shape* s : shapes) cdf.push_back(float(total += s->surface_area()));
        for (float& c : cdf) c = float(c / total);
        if (!cdf.empty()) cdf.back() = 1.f;
    }
    ShapeSample sample(Pcg32& rng) const {
        const float u = rng.next_float();
        const size_t i = std::min(size_t(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()),
                                  shapes.size() - 1);
        return shapes[i]->sample_area({rng.next_float(), rng.next_float()});
    }
};

// Spreads the low 21 bits of x so that bit b moves to bit 3b (a Morton code's one axis).
uint64_t spread_bits(uint64_t x) {
    x &= 0x1fffffu;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
}

}  // namespace

const char* kind_name(RawRays::Kind kind) {
    switch (kind) {
        case RawRays::Kind::incoherent:
            return "incoherent";
        case RawRays::Kind::sorted:
            return "sorted";
        case RawRays::Kind::shadow:
            return "shadow";
    }
    return "?";
}

RawRays::RawRays(const Scene& scene, size_t count, uint64_t seed)
    : embree_(std::make_unique<detail::EmbreeScene>(scene.shapes())) {
    AreaSampler surfaces, lights;
    for (const Shape* shape : embree_->shapes()) {
        if (!shape) continue;  // left out of the BVH (an invisible `null` surface)
        surfaces.shapes.push_back(shape);
        if (shape->emitter()) lights.shapes.push_back(shape);
    }
    if (surfaces.shapes.empty())
        throw std::runtime_error("the scene has no visible surface to start raw rays from");
    surfaces.finish(), lights.finish();
    Pcg32 rng(seed, 1);
    incoherent_.resize(count);
    for (CompactRay& r : incoherent_) {  // offset along the normal as Hit::spawn does
        const ShapeSample s = surfaces.sample(rng);
        r.d = Frame(s.n).to_world(
            warp::square_to_uniform_hemisphere({rng.next_float(), rng.next_float()}));
        r.o = offset_origin(s.p, s.n, r.d, s.p_error);
        r.tmax = kInfinity;
    }
    // Sorted: consecutive rays start close together, as in a renderer tracing one tile.
    Bounds3 b;
    for (const CompactRay& r : incoherent_) b.expand(r.o);
    std::vector<std::pair<uint64_t, uint32_t>> keys(count);
    for (size_t i = 0; i < count; ++i) {
        uint64_t key = 0;
        for (int a = 0; a < 3; ++a) {
            const float extent = b.max[a] - b.min[a];
            const float t = extent > 0 ? (incoherent_[i].o[a] - b.min[a]) / extent : 0.f;
            key |= spread_bits(uint64_t(clamp(t, 0.f, 1.f) * 2097151.f)) << a;
        }
        keys[i] = {key, uint32_t(i)};
    }
    std::sort(keys.begin(), keys.end());
    for (const auto& k : keys) sorted_.push_back(incoherent_[k.second]);
    if (lights.shapes.empty()) return;
    shadow_.resize(count);
    for (CompactRay& r : shadow_) {  // stopping short of the light, as Hit::spawn_to does
        const ShapeSample s = surfaces.sample(rng), l = lights.sample(rng);
        r.o = offset_origin(s.p, s.n, l.p - s.p, s.p_error);
        const Vec3 d = l.p - r.o;
        const float dist = length(d);
        r.d = dist > 0 ? d / dist : s.n;
        r.tmax = shadow_ray_length(dist, l.p);
    }
}

RawRays::~RawRays() = default;

RawRays::Rate RawRays::trace(Kind kind, int threads, double min_seconds) const {
    const std::vector<CompactRay>& rays = kind == Kind::incoherent ? incoherent_
                                          : kind == Kind::sorted   ? sorted_
                                                                   : shadow_;
    Rate rate;
    if (rays.empty()) return rate;
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                              threads > 0 ? size_t(threads) : std::thread::hardware_concurrency());
    const RTCScene scene = embree_->get();
    const double cpu0 = process_cpu_seconds();
    const auto t0 = Clock::now();
    do {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 1024),
                          [&](const tbb::blocked_range<size_t>& range) {
                              enable_flush_to_zero();
                              RTCIntersectContext ctx;
                              rtcInitIntersectContext(&ctx);
                              for (size_t i = range.begin(); i != range.end(); ++i) {
                                  const CompactRay& r = rays[i];
                                  if (kind == Kind::shadow) {
                                      RTCRay ray;
                                      detail::init_ray(ray, r.o, r.d, 0.f, r.tmax);
                                      rtcOccluded1(scene, &ctx, &ray);
                                  } else {
                                      RTCRayHit rh;
                                      detail::init_rayhit(rh, r.o, r.d, 0.f, r.tmax);
                                      rtcIntersect1(scene, &ctx, &rh);
                                  }
                              }
                          });
        rate.rays += rays.size();
        rate.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    } while (rate.seconds < min_seconds);
    rate.cpu_seconds = process_cpu_seconds() - cpu0;
    return rate;
}

}  // namespace femto::bench
