// femto_micro: Google Benchmark micro benchmarks of the routines every camera path runs per
// vertex or per sample (issue 17): the sampler's draws, a light sample, a hit record's fill,
// a film splat, a connection strategy's density, and one whole path-traced (or BDPT) camera
// sample. Each works on the Cornell box of
// bench/experiments/scenes/cornell-films.xml (the shipped room), so its figures are the costs
// that bench/README.md's profile of that scene adds up. A regression in one routine shows here
// before it is lost in a whole render's noise.
//
//   build/bin/femto_micro                                   # all, Google Benchmark's defaults
//   build/bin/femto_micro --benchmark_filter=Splat          # one family
//   build/bin/femto_micro --benchmark_format=json > out.json   (csv needs one counter set)
//
// ctest runs it once with a tiny minimum time (bench_micro_smoke): the check is that every
// routine still runs, never how fast (timed assertions are not tests; docs/architecture.md §8).
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "femto/film.h"
#include "femto/host.h"
#include "femto/integrator.h"
#include "femto/random.h"
#include "femto/scene.h"
#include "femto/sensor.h"
#include "femto/shape.h"
#include "femto/time_sampling.h"
#include "femto/warp.h"

namespace {

using namespace femto;

// The Cornell box with `film` (hdrfilm or transient), 64x64, path tracer, no roulette.
std::unique_ptr<Scene> cornell_box(const std::string& film, const std::string& rfilter = "box",
                                   const std::string& integrator = "path") {
    LoadOptions options;
    options.defines = {
        {"film", film}, {"res", "64"}, {"integrator", integrator}, {"rfilter", rfilter}};
    return load_scene(
        std::string(FEMTO_BENCH_SOURCE_DIR) + "/bench/experiments/scenes/cornell-films.xml",
        options);
}

// Uniform numbers for the routines' inputs, drawn before the timed loop.
std::vector<Vec2> uniform_points(size_t n, uint64_t seed) {
    Pcg32 rng(seed, 1);
    std::vector<Vec2> u(n);
    for (Vec2& v : u) v = {rng.next_float(), rng.next_float()};
    return u;
}

constexpr size_t kInputs = 4096;  // a power of two: inputs cycle with a mask

// ---- sampler draws -------------------------------------------------------------------------

// One camera sample's numbers: start(), then `dims` 2D draws (a path of a few vertices takes
// about 2 + 3 per vertex); range(1) samples of a pixel in a row (8: as the renderer takes them;
// 1: a new pixel every sample).
void SamplerDraw(benchmark::State& state, const std::string& type) {
    Properties props;
    auto sampler =
        std::static_pointer_cast<Sampler>(create_object(PluginKind::Sampler, type, props));
    const int dims = int(state.range(0));
    const uint32_t in_a_row = uint32_t(state.range(1));
    uint32_t sample = 0;
    for (auto _ : state) {
        const uint32_t run = sample / in_a_row;
        sampler->start(7, run & 0xfffu, (run >> 12) * in_a_row + sample % in_a_row);
        ++sample;
        float sum = 0;
        for (int d = 0; d < dims; ++d) {
            const Vec2 u = sampler->next_2d();
            sum += u.x + u.y;
        }
        benchmark::DoNotOptimize(sum);
    }
    state.SetItemsProcessed(state.iterations() * dims);
}
BENCHMARK_CAPTURE(SamplerDraw, ldsampler, std::string("ldsampler"))
    ->Args({1, 1})
    ->Args({16, 1})
    ->Args({16, 8});
BENCHMARK_CAPTURE(SamplerDraw, independent, std::string("independent"))
    ->Args({1, 1})
    ->Args({16, 1});

// Draws as BDPT makes them: each subpath vertex or connection starts at a dimension block of
// its own (Sampler::advance_to, 8 dimensions apart) and takes a few numbers of it: here 16
// draws in blocks of state.range(0).
void SamplerDrawInBlocks(benchmark::State& state) {
    Properties props;
    auto sampler =
        std::static_pointer_cast<Sampler>(create_object(PluginKind::Sampler, "ldsampler", props));
    const int per_block = int(state.range(0));
    uint32_t sample = 0;
    for (auto _ : state) {
        sampler->start(7, sample & 0xfffu, sample >> 12);
        ++sample;
        float sum = 0;
        for (int d = 0; d < 16; ++d) {
            if (d % per_block == 0) sampler->advance_to(uint64_t(d / per_block + 1) * 8);
            const Vec2 u = sampler->next_2d();
            sum += u.x + u.y;
        }
        benchmark::DoNotOptimize(sum);
    }
    state.SetItemsProcessed(state.iterations() * 16);
}
BENCHMARK(SamplerDrawInBlocks)->Arg(1)->Arg(2)->Arg(4);

void SamplerDraw1d(benchmark::State& state) {
    Properties props;
    auto sampler =
        std::static_pointer_cast<Sampler>(create_object(PluginKind::Sampler, "ldsampler", props));
    uint32_t sample = 0;
    for (auto _ : state) {
        sampler->start(7, sample & 0xfffu, sample >> 12);
        ++sample;
        float sum = 0;
        for (int d = 0; d < 16; ++d) sum += sampler->next_1d();
        benchmark::DoNotOptimize(sum);
    }
    state.SetItemsProcessed(state.iterations() * 16);
}
BENCHMARK(SamplerDraw1d);

// ---- warps ---------------------------------------------------------------------------------

// A cosine-weighted direction (the concentric disk lifted to the hemisphere): every diffuse
// bounce and every emission from an area light draws one.
void CosineHemisphere(benchmark::State& state) {
    const auto u = uniform_points(kInputs, 7);
    size_t i = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(warp::square_to_cosine_hemisphere(u[i & (kInputs - 1)]));
        ++i;
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(CosineHemisphere);

// ---- light sample --------------------------------------------------------------------------

// Scene::sample_emitter from points on the floor toward the box's area light: emitter
// selection, a point on its two triangles, the solid-angle density.
void LightSample(benchmark::State& state) {
    auto scene = cornell_box("hdrfilm");
    const auto u = uniform_points(kInputs, 3), ref = uniform_points(kInputs, 4);
    size_t i = 0;
    for (auto _ : state) {
        const Vec2 r = ref[i & (kInputs - 1)];
        const EmitterSample s =
            scene->sample_emitter(Vec3(2 * r.x - 1, -1.f, 2 * r.y - 1), r.x, u[i & (kInputs - 1)]);
        benchmark::DoNotOptimize(s.pdf);
        ++i;
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(LightSample);

// Shape::sample_area on a mesh of 2 n^2 triangles of unequal areas (a UV sphere of n x n
// segments, as a mesh light would be): the choice of a triangle by area dominates.
void MeshAreaSample(benchmark::State& state) {
    const int n = int(state.range(0));
    const std::filesystem::path obj = std::filesystem::temp_directory_path() /
                                      ("femto_micro_sphere_" + std::to_string(n) + ".obj");
    {
        std::ofstream out(obj);
        for (int i = 0; i <= n; ++i)
            for (int j = 0; j <= n; ++j) {
                const double theta = kPi * i / n, phi = 2 * kPi * j / n;
                out << "v " << std::sin(theta) * std::cos(phi) << ' '
                    << std::sin(theta) * std::sin(phi) << ' ' << std::cos(theta) << '\n';
            }
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) {
                const int a = i * (n + 1) + j + 1, b = a + 1, c = a + n + 1, d = c + 1;
                out << "f " << a << ' ' << c << ' ' << d << "\nf " << a << ' ' << d << ' ' << b
                    << '\n';
            }
    }
    Properties props("obj", {});
    props.set_string("filename", obj.string());
    auto shape = std::static_pointer_cast<Shape>(create_object(PluginKind::Shape, "obj", props));
    std::filesystem::remove(obj);
    const auto u = uniform_points(kInputs, 3);
    size_t i = 0;
    for (auto _ : state) {
        const ShapeSample s = shape->sample_area(u[i & (kInputs - 1)]);
        benchmark::DoNotOptimize(s.p);
        ++i;
    }
    state.SetItemsProcessed(state.iterations());
    state.counters["triangles"] = double(shape->mesh().triangle_count());
}
BENCHMARK(MeshAreaSample)->Arg(4)->Arg(64);

// ---- hit fill ------------------------------------------------------------------------------

// Shape::fill_hit for hits on the box's walls (the record every intersection builds: position,
// normals, frame, uv, tangent), from hits found once before the timed loop.
void HitFill(benchmark::State& state) {
    auto scene = cornell_box("hdrfilm");
    const Sensor& sensor = scene->sensor();
    struct Found {
        Ray ray;
        Hit hit;
    };
    std::vector<Found> found;
    const auto u = uniform_points(kInputs, 5);
    for (const Vec2& p : u) {
        Found f{sensor.sample_ray({p.x * 64, p.y * 64}, {0.5f, 0.5f}), {}};
        if (scene->intersect(f.ray, f.hit)) found.push_back(f);
    }
    size_t i = 0;
    for (auto _ : state) {
        const Found& f = found[i % found.size()];
        Hit hit;
        // Fixed barycentrics: the fill's cost does not depend on where in the triangle it is.
        f.hit.shape->fill_hit(f.ray, f.hit.t, f.hit.prim, 0.25f, 0.5f, hit);
        benchmark::DoNotOptimize(hit.sh);
        ++i;
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(HitFill);

// Scene::intersect, Embree's traversal and the fill together, for the same camera rays.
void Intersect(benchmark::State& state) {
    auto scene = cornell_box("hdrfilm");
    const Sensor& sensor = scene->sensor();
    std::vector<Ray> rays;
    for (const Vec2& p : uniform_points(kInputs, 6))
        rays.push_back(sensor.sample_ray({p.x * 64, p.y * 64}, {0.5f, 0.5f}));
    size_t i = 0;
    for (auto _ : state) {
        Hit hit;
        benchmark::DoNotOptimize(scene->intersect(rays[i & (kInputs - 1)], hit));
        ++i;
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(Intersect);

// ---- film splat ----------------------------------------------------------------------------

// FilmBlock::put of one camera sample of `contributions` contributions at random times
// inside the window, into a 32x32 tile's block: hdrfilm or a 1024-bin transient film, with
// the box or the Gaussian reconstruction filter. The block merges into the film after every
// 2,048 samples, as a render's pass of 2 spp would (a transient block grows with what it holds).
void Splat(benchmark::State& state, const std::string& film, const std::string& rfilter) {
    auto scene = cornell_box(film, rfilter);
    Film& f = scene->sensor().film();
    auto block = f.make_block(0, 0, 32, 32);
    const auto pos = uniform_points(kInputs, 7), t = uniform_points(kInputs, 8);
    const int contributions = int(state.range(0));
    ContributionList list;
    size_t i = 0;
    for (auto _ : state) {
        const size_t k = i & (kInputs - 1);
        list.clear();
        for (int c = 0; c < contributions; ++c)
            list.add(Color(0.5f, 0.25f, 0.125f), 3.6 + 25.0 * double(t[(k + c) & (kInputs - 1)].x));
        list.set_sensor_distance(4.0);
        block->put({pos[k].x * 32, pos[k].y * 32}, list);
        if (++i % 2048 == 0) f.merge(*block);
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(Splat, hdrfilm_box, std::string("hdrfilm"), std::string("box"))->Arg(4);
BENCHMARK_CAPTURE(Splat, hdrfilm_gaussian, std::string("hdrfilm"), std::string("gaussian"))->Arg(4);
BENCHMARK_CAPTURE(Splat, transient_box, std::string("transient"), std::string("box"))->Arg(4);
BENCHMARK_CAPTURE(Splat, transient_gaussian, std::string("transient"), std::string("gaussian"))
    ->Arg(4);

// ---- connection strategies -----------------------------------------------------------------

// The equiangular density of a distance on a segment toward a point: a connection strategy's
// term in every MIS weight of a BDPT path through a medium (per vertex and strategy), on
// segments and targets of the box's size.
void EquiangularPdf(benchmark::State& state) {
    const auto a = uniform_points(kInputs, 5), b = uniform_points(kInputs, 6);
    std::vector<ConnectionQuery> queries(kInputs);
    for (size_t i = 0; i < kInputs; ++i)
        queries[i] = {Vec3(0.f, -0.5f, 0.f), normalize(Vec3(a[i].x - 0.5f, 0.3f, a[i].y - 0.5f)),
                      0.5 + 2.0 * b[i].x, Vec3(2 * b[i].y - 1, 0.9f, 0.2f)};
    size_t i = 0;
    for (auto _ : state) {
        const ConnectionQuery& q = queries[i & (kInputs - 1)];
        benchmark::DoNotOptimize(equiangular_pdf(q, 0.5 * q.length));
        ++i;
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(EquiangularPdf);

// ---- one camera sample ---------------------------------------------------------------------

// Integrator::sample for one camera ray of the box, max_depth 8, no roulette: everything above
// together, plus Embree (the ray rate's denominator). BDPT's sample also keeps its splats (the
// strategies t = 1), dropped before the next.
void PathSample(benchmark::State& state, const std::string& integrator) {
    auto scene = cornell_box("hdrfilm", "box", integrator);
    scene->integrator().preprocess(*scene);  // as render() does (BDPT's light starts)
    const Sensor& sensor = scene->sensor();
    auto sampler = sensor.sampler().clone();
    const Integrator& path = scene->integrator();
    ContributionList list;
    SplatList splats;
    if (path.splats()) list.set_splat_list(&splats);
    uint32_t s = 0;
    const uint64_t rays_before = scene->rays_traced();
    for (auto _ : state) {
        const uint32_t pixel = s & 4095u;
        sampler->start(1, pixel, s >> 12);
        const Vec2 jitter = sampler->next_2d();
        const Ray ray = sensor.sample_ray(
            {float(pixel % 64) + jitter.x, float(pixel / 64) + jitter.y}, sampler->next_2d());
        list.clear();
        splats.clear();
        path.sample(*scene, *sampler, ray, list);
        benchmark::DoNotOptimize(list.items().data());
        ++s;
    }
    state.SetItemsProcessed(state.iterations());
    state.counters["rays_per_sample"] =
        double(scene->rays_traced() - rays_before) / double(state.iterations());
}
BENCHMARK_CAPTURE(PathSample, path, std::string("path"));
BENCHMARK_CAPTURE(PathSample, transient_path, std::string("transient_path"));
BENCHMARK_CAPTURE(PathSample, transient_bdpt, std::string("transient_bdpt"));

}  // namespace

BENCHMARK_MAIN();
