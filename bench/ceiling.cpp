// femto_bench_ceiling: how near to Embree's raw ray rate a path tracer of femto's kind can come
// at all (issue 17's yardstick: `path` at >= 0.7x the raw incoherent rate on the Cornell box).
// In one process, in interleaved rounds on one scene, it measures
//   raw      Embree alone on random incoherent rays (bench::RawRays, as `femto bench` <raw_rays>);
//   minimal  a path tracer written for speed and nothing else, in this file: the same BVH
//            (detail::EmbreeScene), the same camera rays (the scene's sensor), the same paths
//            (max_depth segments, next-event estimation at every vertex that may still add
//            one, no roulette) but a grey Lambertian surface everywhere, Embree's geometric
//            normal, a PCG draw per number, lights sampled by area from a flat table, and one
//            add per sample into a float image: the least work per ray such a tracer can do;
//   femto    the `path` plugin rendering the scene (femto::render, the scene's sampler, film and
//            materials).
// Each rate is every ray traced (camera, bounce, shadow) over the wall-clock seconds. What
// femto's rate lacks of the minimal one is femto's overhead; what the minimal one lacks of the
// raw rate is the work any such path tracer must do between rays.
//
//   femto_bench_ceiling [--rounds 7] [--threads 1] [--spp 8] [--res 256] [--out FILE.csv]
#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <pmmintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <xmmintrin.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <numbers>

#include "accel/embree_scene.h"
#include "bench/raw_rays.h"
#include "common.h"
#include "femto/bsdf.h"
#include "femto/integrator.h"
#include "femto/random.h"
#include "femto/sampler.h"
#include "femto/shape.h"

namespace {

using femto::Vec2;
using femto::Vec3;
using Clock = std::chrono::steady_clock;

struct LightTriangle {
    Vec3 v0, e1, e2, n;  // n: unit, the side the light leaves from
};

// femto's own pieces the minimal tracer can use instead of its bare ones, one at a time, to
// price each: the scene's sampler plugin for every number, Hit records (detail::EmbreeScene::
// fill_hit, Hit::spawn and spawn_to), light samples (Scene::sample_emitter), and the surfaces'
// material plugins (Bsdf::sample and eval; they need Hit records).
struct Pieces {
    std::string name;
    bool sampler = false, hit = false, light = false, bsdf = false;
};

// The numbers of one camera sample: PCG, or the scene's sampler plugin.
class Numbers {
public:
    Numbers(femto::Sampler* plugin, uint64_t seed, uint64_t pixel, uint32_t sample)
        : plugin_(plugin), rng_(femto::hash_combine(seed, sample), pixel) {
        if (plugin_) plugin_->start(seed, pixel, sample);
    }
    float next_1d() { return plugin_ ? plugin_->next_1d() : rng_.next_float(); }
    Vec2 next_2d() {
        if (plugin_) return plugin_->next_2d();
        const float x = rng_.next_float();
        return {x, rng_.next_float()};
    }

private:
    femto::Sampler* plugin_;
    femto::Pcg32 rng_;
};

// The minimal path tracer over the scene's geometry; see the file's comment.
class MinimalPathTracer {
public:
    MinimalPathTracer(const femto::Scene& scene, int max_depth)
        : scene_(scene), embree_(scene.shapes()), max_depth_(max_depth) {
        double total = 0;
        for (const femto::Shape* shape : embree_.shapes()) {
            if (!shape || !shape->emitter() || shape->is_sphere() || shape->is_cylinder()) continue;
            const femto::TriangleMesh& m = shape->mesh();
            for (size_t t = 0; t < m.triangle_count(); ++t) {
                const Vec3 a = m.positions[m.indices[3 * t]], b = m.positions[m.indices[3 * t + 1]],
                           c = m.positions[m.indices[3 * t + 2]];
                const Vec3 g = femto::cross(b - a, c - a);
                const float area = 0.5f * femto::length(g);
                if (!(area > 0)) continue;
                lights_.push_back(
                    {a, b - a, c - a, femto::normalize(shape->flip_normals() ? -g : g)});
                cdf_.push_back(float(total += area));
            }
        }
        if (lights_.empty()) throw std::runtime_error("the scene has no triangle light");
        for (float& c : cdf_) c = float(c / total);
        cdf_.back() = 1.f;
        light_area_ = float(total);
    }

    struct Result {
        uint64_t rays = 0, samples = 0;
        double seconds = 0, mean = 0;
    };

    Result render(int width, int height, int spp, uint64_t seed, const Pieces& pieces) const {
        std::vector<float> image(size_t(width) * size_t(height), 0.f);
        tbb::enumerable_thread_specific<uint64_t> rays(0);
        tbb::enumerable_thread_specific<std::unique_ptr<femto::Sampler>> samplers(
            [&] { return scene_.sensor().sampler().clone(); });
        const auto t0 = Clock::now();
        tbb::parallel_for(
            tbb::blocked_range<int>(0, height, 4), [&](const tbb::blocked_range<int>& rows) {
                _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
                _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
                uint64_t& count = rays.local();
                femto::Sampler* plugin = pieces.sampler ? samplers.local().get() : nullptr;
                for (int y = rows.begin(); y != rows.end(); ++y)
                    for (int x = 0; x < width; ++x) {
                        const uint64_t pixel = uint64_t(y) * uint64_t(width) + uint64_t(x);
                        float sum = 0.f;
                        for (int s = 0; s < spp; ++s) {
                            Numbers numbers(plugin, seed, pixel, uint32_t(s));
                            sum += sample(x, y, numbers, pieces, count);
                        }
                        image[size_t(pixel)] += sum / float(spp);
                    }
            });
        Result r;
        r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        for (uint64_t n : rays) r.rays += n;
        r.samples = uint64_t(width) * uint64_t(height) * uint64_t(spp);
        double total = 0;
        for (float v : image) total += v;
        r.mean = total / double(image.size());
        return r;
    }

private:
    static constexpr float kAlbedo = 0.5f, kEpsilon = 1e-4f;
    static constexpr float kInvPi = std::numbers::inv_pi_v<float>;

    // A vertex as the path continues from it: the bare version, or femto's Hit.
    struct Vertex {
        Vec3 p, n;  // p already offset along n (bare); n faces the incoming ray
        femto::Hit hit;
    };

    // One camera sample: radiance of a scene whose surfaces are all grey Lambertian (or their
    // materials, with `bsdf`) and whose lights emit 1 (or their emission, with `light`):
    // emission seen directly, then next-event estimation at each vertex.
    float sample(int x, int y, Numbers& numbers, const Pieces& pieces, uint64_t& rays) const {
        const Vec2 film = numbers.next_2d();
        femto::Ray ray = scene_.sensor().sample_ray(Vec2(float(x) + film.x, float(y) + film.y),
                                                    Vec2(0.5f, 0.5f));
        float radiance = 0.f, beta = 1.f;
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        Vertex v;
        for (int depth = 1;; ++depth) {
            RTCRayHit rh;
            femto::detail::init_rayhit(rh, ray.o, ray.d, ray.tmin, ray.tmax);
            rtcIntersect1(embree_.get(), &ctx, &rh);
            ++rays;
            if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
            const femto::Shape* shape = embree_.shapes()[rh.hit.geomID];
            if (pieces.hit) {
                embree_.fill_hit(ray, rh, v.hit);
                v.n = femto::dot(v.hit.ng, ray.d) > 0 ? -v.hit.ng : v.hit.ng;
            } else {
                v.n = femto::normalize(Vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
                if (femto::dot(v.n, ray.d) > 0) v.n = -v.n;
                v.p = ray.o + ray.d * rh.ray.tfar + v.n * kEpsilon;
            }
            if (depth == 1 && shape && shape->emitter()) radiance += beta;
            if (depth >= max_depth_) break;
            radiance += beta * direct(v, numbers, pieces, rays);
            if (!bounce(v, numbers, pieces, ray, beta)) break;
        }
        return radiance;
    }

    // Reflected light from one light sample: one shadow ray.
    float direct(const Vertex& v, Numbers& numbers, const Pieces& pieces, uint64_t& rays) const {
        const float u_light = numbers.next_1d();
        const Vec2 u = numbers.next_2d();
        femto::Ray shadow_ray;
        Vec3 w;
        float value = 0.f;
        if (pieces.light) {
            const femto::EmitterSample ls = scene_.sample_emitter(v.hit.p, u_light, u);
            if (!(ls.pdf > 0)) return 0.f;
            const float cos_p = femto::dot(v.n, ls.wi);
            if (cos_p <= 0) return 0.f;
            w = ls.wi;
            shadow_ray = v.hit.spawn_to(ls.p);
            value = ls.weight.g;
        } else {
            const size_t i =
                size_t(std::lower_bound(cdf_.begin(), cdf_.end(), u_light) - cdf_.begin());
            const LightTriangle& l = lights_[std::min(i, lights_.size() - 1)];
            float b1 = u.x, b2 = u.y;
            if (b1 + b2 > 1.f) b1 = 1.f - b1, b2 = 1.f - b2;
            const Vec3 from = pieces.hit ? v.hit.p + v.n * kEpsilon : v.p;
            w = l.v0 + l.e1 * b1 + l.e2 * b2 - from;
            const float dist2 = femto::dot(w, w), dist = std::sqrt(dist2);
            w = w / dist;
            const float cos_l = -femto::dot(l.n, w);
            if (femto::dot(v.n, w) <= 0 || cos_l <= 0) return 0.f;
            shadow_ray = femto::Ray{from, w, 0.f, dist * (1.f - 1e-3f)};
            value = cos_l * light_area_ / dist2;
        }
        if (pieces.bsdf) {
            value *= v.hit.shape->bsdf()->eval(v.hit, v.hit.wi, v.hit.to_local(w)).g;
        } else {
            value *= kAlbedo * kInvPi * femto::dot(v.n, w);
        }
        RTCRay shadow;
        femto::detail::init_ray(shadow, shadow_ray.o, shadow_ray.d, shadow_ray.tmin,
                                shadow_ray.tmax);
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        rtcOccluded1(embree_.get(), &ctx, &shadow);
        ++rays;
        return shadow.tfar < 0 ? 0.f : value;
    }

    // The next direction; false when the path ends.
    bool bounce(const Vertex& v, Numbers& numbers, const Pieces& pieces, femto::Ray& ray,
                float& beta) const {
        if (pieces.bsdf) {
            const float u_lobe = numbers.next_1d();
            const femto::BsdfSample bs =
                v.hit.shape->bsdf()->sample(v.hit, v.hit.wi, u_lobe, numbers.next_2d());
            if (!bs.valid()) return false;
            beta *= bs.weight.g;
            ray = v.hit.spawn(v.hit.to_world(bs.wo));
            return true;
        }
        const Vec2 u = numbers.next_2d();
        const Vec3 d = cosine_direction(v.n, u.x, u.y);
        ray = pieces.hit ? v.hit.spawn(d) : femto::Ray{v.p, d, 0.f, femto::kInfinity};
        beta *= kAlbedo;
        return true;
    }

    // Cosine-weighted around n (Duff et al.'s branchless basis).
    static Vec3 cosine_direction(const Vec3& n, float u1, float u2) {
        const float sign = std::copysign(1.f, n.z), a = -1.f / (sign + n.z), b = n.x * n.y * a;
        const Vec3 s(1.f + sign * n.x * n.x * a, sign * b, -sign * n.x),
            t(b, sign + n.y * n.y * a, -n.y);
        const float r = std::sqrt(u1), phi = 2.f * std::numbers::pi_v<float> * u2;
        return s * (r * std::cos(phi)) + t * (r * std::sin(phi)) + n * std::sqrt(1.f - u1);
    }

    const femto::Scene& scene_;
    femto::detail::EmbreeScene embree_;
    int max_depth_;
    std::vector<LightTriangle> lights_;
    std::vector<float> cdf_;
    float light_area_ = 0.f;
};

struct Measure {
    std::string variant;
    double rays_per_second = 0, rays_per_sample = 0, over_raw = 0;
};

using namespace femto_bench;  // median(), now_utc(), cpu_model(), read_loadavg()

// Rounds of Embree's raw incoherent rays, the minimal tracer's ladder and femto's `path`,
// interleaved, each round's rates over that round's raw rate.
std::vector<Measure> measure_rounds(femto::Scene& scene, const femto::bench::RawRays& raw,
                                    const MinimalPathTracer& minimal, int rounds, int threads,
                                    int res, int spp) {
    const std::vector<Pieces> ladder = {{"minimal"},
                                        {"minimal + sampler", true},
                                        {"minimal + hit", false, true},
                                        {"minimal + hit + light", false, true, true},
                                        {"minimal + hit + bsdf", false, true, false, true},
                                        {"minimal + all four", true, true, true, true}};
    std::vector<Measure> measures;
    for (int r = 0; r < rounds; ++r) {
        const auto rate = raw.trace(femto::bench::RawRays::Kind::incoherent, threads, 1.0);
        const double raw_rate = double(rate.rays) / rate.seconds;
        measures.push_back({"raw incoherent", raw_rate, 0, 1.0});
        for (const Pieces& pieces : ladder) {
            const auto m = minimal.render(res, res, spp, uint64_t(r) + 1, pieces);
            const double rps = double(m.rays) / m.seconds;
            measures.push_back(
                {pieces.name, rps, double(m.rays) / double(m.samples), rps / raw_rate});
        }
        femto::RenderOptions ro;
        ro.threads = threads;
        ro.seed = uint64_t(r) + 1;
        const femto::RenderStats st = femto::render(scene, ro);
        const double rps = double(st.rays) / st.seconds;
        measures.push_back(
            {"femto path", rps, double(st.rays) / double(st.camera_samples), rps / raw_rate});
        fmt::print("round {} of {} done\n", r + 1, rounds);
    }
    return measures;
}

// Each variant's medians over the rounds, in the order the variants first appear.
void print_medians(const std::vector<Measure>& measures) {
    std::vector<std::string> variants;
    for (const Measure& m : measures)
        if (std::find(variants.begin(), variants.end(), m.variant) == variants.end())
            variants.push_back(m.variant);
    fmt::print("{:<24} {:>10} {:>12} {:>10}\n", "variant", "Mrays/s", "rays/sample", "over raw");
    for (const std::string& v : variants) {
        std::vector<double> rps, per_sample, over;
        for (const Measure& m : measures)
            if (m.variant == v) {
                rps.push_back(m.rays_per_second);
                per_sample.push_back(m.rays_per_sample);
                over.push_back(m.over_raw);
            }
        fmt::print("{:<24} {:>10.2f} {:>12.3f} {:>10.3f}\n", v, median(rps) * 1e-6,
                   median(per_sample), median(over));
    }
}

// The minimal tracer must trace femto's paths (same camera rays, depths and shadow rays), or
// its rate is not comparable: rays per camera sample agree within 3 % (about four standard
// errors at 32x32 and 4 spp, the smoke test's size).
void require_same_paths(const std::vector<Measure>& measures) {
    std::vector<double> minimal_per_sample, femto_per_sample;
    for (const Measure& m : measures) {
        if (m.variant == "minimal") minimal_per_sample.push_back(m.rays_per_sample);
        if (m.variant == "femto path") femto_per_sample.push_back(m.rays_per_sample);
    }
    const double a = median(minimal_per_sample), b = median(femto_per_sample);
    if (!(std::abs(a - b) <= 0.03 * b))
        throw std::runtime_error(fmt::format(
            "the minimal tracer traced {:.3f} rays a camera sample and femto {:.3f}: they do "
            "not trace the same paths",
            a, b));
}

void write_csv(const std::string& out, const std::vector<Measure>& measures, int rounds,
               int threads, int res, int spp) {
    std::ofstream csv(out);
    if (!csv) throw std::runtime_error("cannot write " + out);
    csv << "# femto_bench_ceiling, " << now_utc() << ", " << cpu_model() << ", load "
        << read_loadavg() << ", threads " << threads << ", " << res << "x" << res << ", " << spp
        << " spp, build " << FEMTO_BENCH_BUILD << "\n";
    csv << "round,variant,rays_per_s,rays_per_sample,over_raw\n";
    const size_t per_round = measures.size() / size_t(rounds);
    for (size_t i = 0; i < measures.size(); ++i) {
        const Measure& m = measures[i];
        csv << fmt::format("{},{},{:.0f},{:.3f},{:.4f}\n", i / per_round + 1, m.variant,
                           m.rays_per_second, m.rays_per_sample, m.over_raw);
    }
    if (!csv.flush()) throw std::runtime_error("cannot write " + out);
}

}  // namespace

int main(int argc, char** argv) {
    try {
        std::setvbuf(stdout, nullptr, _IOLBF, 0);
        int rounds = 7, threads = 1, spp = 8, res = 256;
        std::string out =
            std::string(FEMTO_BENCH_SOURCE_DIR) + "/bench/results/ceiling/ceiling.csv";
        parse_options(
            argc, argv,
            {{"--rounds", &rounds}, {"--threads", &threads}, {"--spp", &spp}, {"--res", &res}},
            {{"--out", &out}});
        if (rounds < 1 || threads < 1 || spp < 1 || res < 1 || res > 4096)
            throw std::invalid_argument("rounds, threads, spp >= 1; res in [1, 4096]");
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        femto::LoadOptions options;
        options.defines = {{"integrator", "path"},
                           {"film", "hdrfilm"},
                           {"res", std::to_string(res)},
                           {"spp", std::to_string(spp)}};
        const std::string file =
            std::string(FEMTO_BENCH_SOURCE_DIR) + "/bench/experiments/scenes/cornell-films.xml";
        auto scene = femto::load_scene(file, options);
        const femto::bench::RawRays raw(*scene, size_t(1) << 20, 1);
        const auto* path = dynamic_cast<const femto::MonteCarloIntegrator*>(&scene->integrator());
        if (!path || path->max_depth() < 1 || path->rr_depth() != 0)
            throw std::runtime_error(
                "the scene's path integrator needs a max_depth and no roulette");
        const MinimalPathTracer minimal(*scene, int(path->max_depth()));
        const std::vector<Measure> measures =
            measure_rounds(*scene, raw, minimal, rounds, threads, res, spp);
        fmt::print("medians over {} rounds, {} thread(s), {}x{}, {} spp:\n", rounds, threads, res,
                   res, spp);
        print_medians(measures);
        require_same_paths(measures);
        write_csv(out, measures, rounds, threads, res, spp);
        fmt::print("wrote {}\n", out);
        return 0;
    } catch (const std::exception& e) {
        fmt::print(stderr, "femto_bench_ceiling: {}\n", e.what());
        return 2;
    }
}
