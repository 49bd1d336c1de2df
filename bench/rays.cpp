// femto_bench_rays: the `path` integrator's ray rate next to Embree's raw rate, side by side.
//
// For each scene (the Cornell box from scenes/, rendered with `path` into an `hdrfilm`, and a
// procedurally generated room holding a displaced sphere of >= 1M triangles, written as a
// binary PLY) and each thread count:
//
//  - raw: an Embree scene built from the loaded femto scene's shapes by the renderer's own
//    construction (femto::detail::EmbreeScene, host/src/accel/embree_scene.h: same geometry,
//    RTC_BUILD_QUALITY_MEDIUM, RTC_SCENE_FLAG_ROBUST), traced with rtcIntersect1 over an
//    array of pre-generated random incoherent rays: origins uniform by area over all
//    surfaces (Shape::sample_area), offset along the normal as femto offsets its own rays,
//    directions uniform on the hemisphere around the normal.
//    Generation is not timed. Informative figures next to it: the same rays sorted by origin
//    (Morton order), and shadow rays (rtcOccluded1) to uniform points on the area lights.
//  - femto: femto::render() of the scene with the `path` integrator at a fixed seed and spp;
//    RenderStats.rays / RenderStats.seconds counts every ray (camera, bounce, shadow).
//
// Runs alternate raw and femto measurements (ABBA order, so drift hits both alike); results
// are medians, by wall clock and per second of process CPU time. Output: a table on stdout,
// <out>/rays.csv (every run), <out>/rays_summary.csv (medians and ratios) and
// <out>/rays_meta.txt (machine, load, settings). See bench/README.md.
#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <pmmintrin.h>
#include <sys/resource.h>
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <unistd.h>
#include <xmmintrin.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <pugixml.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "accel/embree_scene.h"
#include "common.h"
#include "femto/error.h"
#include "femto/host.h"
#include "femto/math.h"
#include "femto/random.h"
#include "femto/scene.h"
#include "femto/shape.h"
#include "femto/warp.h"

namespace fs = std::filesystem;
using femto::Vec2;
using femto::Vec3;

namespace {

using femto_bench::cpu_model;
using femto_bench::cpu_seconds;
using femto_bench::load1;
using femto_bench::median;
using femto_bench::now_utc;
using femto_bench::read_loadavg;
using femto_bench::split;

using Clock = std::chrono::steady_clock;

// -- options ---------------------------------------------------------------------------------

struct Options {
    std::string source_dir = FEMTO_BENCH_SOURCE_DIR;
    std::string out_dir = std::string(FEMTO_BENCH_SOURCE_DIR) + "/bench/results";
    std::string work_dir;     ///< where the generated scene goes (default: a new temp folder)
    std::string preview_dir;  ///< when set, each scene's image is written there once
    bool keep_work = false;
    int runs = 7;
    std::vector<int> threads = {1, 2};
    std::vector<std::string> scenes = {"cornell-box", "displaced-sphere"};
    int res = 256;
    uint32_t cornell_spp = 16;
    uint32_t sphere_spp = 8;
    int rings = 512;  ///< latitude rings of the displaced sphere; 2*rings segments around
    int max_depth = 8;
    size_t raw_rays = size_t(1) << 20;  ///< pre-generated rays, traced in passes
    double raw_seconds = 1.0;           ///< each raw measurement runs at least this long
    uint64_t seed = 1;
    bool raw_robust = true;  ///< RTC_SCENE_FLAG_ROBUST for the raw scene, as the renderer sets
};

void usage() {
    std::puts(
        "usage: femto_bench_rays [options]\n"
        "  --out DIR          results folder (default: <repo>/bench/results)\n"
        "  --source-dir DIR   repository root holding scenes/ (default: the configured one)\n"
        "  --runs N           measurements per scene and thread count (default 7, >= 1)\n"
        "  --threads LIST     comma-separated thread counts (default 1,2)\n"
        "  --scenes LIST      cornell-box,displaced-sphere (default both)\n"
        "  --res N            image width and height for the femto renders (default 256)\n"
        "  --cornell-spp N    samples per pixel, Cornell box (default 16)\n"
        "  --sphere-spp N     samples per pixel, displaced sphere (default 8)\n"
        "  --rings N          displaced-sphere rings; triangles = 4 N (N - 1) (default 512)\n"
        "  --max-depth N      path integrator max_depth (default 8)\n"
        "  --raw-rays N       pre-generated raw rays (default 1048576)\n"
        "  --raw-seconds S    minimum duration of one raw measurement (default 1.0)\n"
        "  --seed N           render and ray-generation seed (default 1)\n"
        "  --work-dir DIR     where to write the generated scene (default: a temp folder)\n"
        "  --keep             keep the generated scene\n"
        "  --preview DIR      also write each scene's image (EXR + PNG) to DIR\n"
        "  --raw-not-robust   diagnostic: build the raw scene without RTC_SCENE_FLAG_ROBUST\n"
        "                     (femto's scene always sets it, so the ratio is then not like\n"
        "                     for like)");
}

long long parse_int(const std::string& flag, const std::string& v, long long lo, long long hi) {
    size_t used = 0;
    long long x = 0;
    try {
        x = std::stoll(v, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != v.size() || x < lo || x > hi)
        throw std::invalid_argument(
            fmt::format("{}: expected an integer in [{}, {}], got '{}'", flag, lo, hi, v));
    return x;
}

double parse_double(const std::string& flag, const std::string& v, double lo, double hi) {
    size_t used = 0;
    double x = 0;
    try {
        x = std::stod(v, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used != v.size() || !(x >= lo && x <= hi))
        throw std::invalid_argument(
            fmt::format("{}: expected a number in [{}, {}], got '{}'", flag, lo, hi, v));
    return x;
}

Options parse_options(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "-h" || a == "--help") {
            usage();
            std::exit(0);
        }
        if (a == "--keep") {
            o.keep_work = true;
            continue;
        }
        if (a == "--raw-not-robust") {
            o.raw_robust = false;
            continue;
        }
        static const char* const kWithValue[] = {
            "--out",     "--source-dir", "--work-dir", "--preview",     "--runs",
            "--threads", "--scenes",     "--res",      "--cornell-spp", "--sphere-spp",
            "--rings",   "--max-depth",  "--raw-rays", "--raw-seconds", "--seed"};
        if (std::find(std::begin(kWithValue), std::end(kWithValue), a) == std::end(kWithValue))
            throw std::invalid_argument("unknown option '" + a + "' (see --help)");
        if (i + 1 >= argc) throw std::invalid_argument(a + ": missing value (see --help)");
        const std::string v = argv[++i];
        if (a == "--out") {
            o.out_dir = v;
        } else if (a == "--source-dir") {
            o.source_dir = v;
        } else if (a == "--work-dir") {
            o.work_dir = v;
        } else if (a == "--preview") {
            o.preview_dir = v;
        } else if (a == "--runs") {
            o.runs = int(parse_int(a, v, 1, 1000));
        } else if (a == "--threads") {
            o.threads.clear();
            for (const auto& t : split(v, ',')) o.threads.push_back(int(parse_int(a, t, 1, 1024)));
            if (o.threads.empty()) throw std::invalid_argument("--threads: empty list");
        } else if (a == "--scenes") {
            o.scenes = split(v, ',');
            for (const auto& s : o.scenes)
                if (s != "cornell-box" && s != "displaced-sphere")
                    throw std::invalid_argument("--scenes: unknown scene '" + s +
                                                "' (valid: cornell-box, displaced-sphere)");
            if (o.scenes.empty()) throw std::invalid_argument("--scenes: empty list");
        } else if (a == "--res") {
            o.res = int(parse_int(a, v, 8, 4096));
        } else if (a == "--cornell-spp") {
            o.cornell_spp = uint32_t(parse_int(a, v, 1, 1 << 20));
        } else if (a == "--sphere-spp") {
            o.sphere_spp = uint32_t(parse_int(a, v, 1, 1 << 20));
        } else if (a == "--rings") {
            o.rings = int(parse_int(a, v, 3, 8192));
        } else if (a == "--max-depth") {
            o.max_depth = int(parse_int(a, v, -1, 1000));
        } else if (a == "--raw-rays") {
            o.raw_rays = size_t(parse_int(a, v, 1024, 1ll << 26));
        } else if (a == "--raw-seconds") {
            o.raw_seconds = parse_double(a, v, 0.0, 3600.0);
        } else if (a == "--seed") {
            o.seed = uint64_t(parse_int(a, v, 0, 1ll << 62));
        } else {
            throw std::invalid_argument("unknown option '" + a + "' (see --help)");
        }
    }
    return o;
}

// -- machine ---------------------------------------------------------------------------------

void enable_flush_to_zero() {
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}

// -- the generated scene: a displaced sphere of >= 1M triangles in a Cornell-style room -------

/// Radius of the bumpy unit sphere at polar angle theta (from +y) and azimuth phi. Every term
/// vanishes at the poles, so the surface stays closed there.
double bump_radius(double theta, double phi) {
    return 1.0 + 0.08 * std::sin(7.0 * theta) * std::sin(9.0 * phi) +
           0.025 * std::sin(29.0 * theta) * std::sin(31.0 * phi + 2.0 * theta) +
           0.006 * std::sin(97.0 * theta) * std::cos(101.0 * phi);
}

template <typename T>
void put_le(std::string& buf, T value) {
    static_assert(sizeof(T) == 4);
    uint32_t bits;
    std::memcpy(&bits, &value, 4);
    for (int i = 0; i < 4; ++i) buf.push_back(char((bits >> (8 * i)) & 0xFFu));
}

/// Writes the sphere as a binary little-endian PLY (positions only: the ply plugin computes
/// smooth normals). Latitude-longitude grid: `rings` bands from pole to pole, 2*rings
/// segments around; 4 * rings * (rings - 1) triangles, wound counter-clockwise seen from
/// outside. Returns the triangle count.
size_t write_displaced_sphere(const fs::path& file, int rings) {
    const uint32_t nu = uint32_t(2 * rings), nv = uint32_t(rings);
    const uint32_t vertex_count = 2 + nu * (nv - 1);
    const size_t triangle_count = size_t(2) * nu * (nv - 1);
    const uint32_t south = vertex_count - 1;
    auto vid = [&](uint32_t i, uint32_t j) { return 1 + (j - 1) * nu + (i % nu); };  // j in [1, nv)

    std::string body;
    body.reserve(size_t(vertex_count) * 12 + triangle_count * 13);
    auto vertex = [&](double theta, double phi) {
        const double r = bump_radius(theta, phi);
        put_le(body, float(r * std::sin(theta) * std::cos(phi)));
        put_le(body, float(r * std::cos(theta)));
        put_le(body, float(r * std::sin(theta) * std::sin(phi)));
    };
    const double pi = 3.14159265358979323846;
    vertex(0.0, 0.0);
    for (uint32_t j = 1; j < nv; ++j)
        for (uint32_t i = 0; i < nu; ++i) vertex(pi * j / nv, 2.0 * pi * i / nu);
    vertex(pi, 0.0);
    auto triangle = [&](uint32_t a, uint32_t b, uint32_t c) {
        body.push_back(char(3));
        put_le(body, int32_t(a));
        put_le(body, int32_t(b));
        put_le(body, int32_t(c));
    };
    for (uint32_t i = 0; i < nu; ++i) triangle(0, vid(i + 1, 1), vid(i, 1));
    for (uint32_t j = 1; j + 1 < nv; ++j)
        for (uint32_t i = 0; i < nu; ++i) {
            const uint32_t a = vid(i, j), b = vid(i + 1, j), c = vid(i + 1, j + 1),
                           d = vid(i, j + 1);
            triangle(a, b, c);
            triangle(a, c, d);
        }
    for (uint32_t i = 0; i < nu; ++i) triangle(vid(i, nv - 1), vid(i + 1, nv - 1), south);

    const std::string header = fmt::format(
        "ply\nformat binary_little_endian 1.0\ncomment femto bench: displaced sphere, {} rings\n"
        "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n"
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        rings, vertex_count, triangle_count);
    std::ofstream f(file, std::ios::binary);
    f.write(header.data(), std::streamsize(header.size()));
    f.write(body.data(), std::streamsize(body.size()));
    if (!f) throw std::runtime_error("cannot write " + file.string());
    return triangle_count;
}

/// The room and light are the Cornell box's; the sphere (radius ~0.55) hovers just above the floor.
constexpr const char* kSphereSceneXml = R"(<?xml version="1.0" encoding="utf-8"?>
<!-- femto bench: a displaced sphere of >= 1M triangles (displaced_sphere.ply, written by
     femto_bench_rays) in a Cornell-style room lit by a small area light. -->
<scene version="3.0.0">
    <default name="spp" value="8"/>
    <default name="res" value="256"/>
    <default name="max_depth" value="8"/>

    <integrator type="path">
        <integer name="max_depth" value="$max_depth"/>
    </integrator>

    <sensor type="perspective">
        <float name="fov" value="39.3077"/>
        <transform name="to_world">
            <lookat origin="0, 0, 3.9" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <rfilter type="box"/>
        </film>
    </sensor>

    <bsdf type="diffuse" id="white">
        <rgb name="reflectance" value="0.725, 0.71, 0.68"/>
    </bsdf>
    <bsdf type="diffuse" id="red">
        <rgb name="reflectance" value="0.63, 0.065, 0.05"/>
    </bsdf>
    <bsdf type="diffuse" id="green">
        <rgb name="reflectance" value="0.14, 0.45, 0.091"/>
    </bsdf>
    <bsdf type="diffuse" id="clay">
        <rgb name="reflectance" value="0.6, 0.45, 0.3"/>
    </bsdf>

    <shape type="rectangle"> <!-- light -->
        <transform name="to_world">
            <scale value="0.23"/>
            <rotate x="1" angle="90"/>
            <translate y="0.99"/>
        </transform>
        <ref id="white"/>
        <emitter type="area">
            <rgb name="radiance" value="17, 12, 4"/>
        </emitter>
    </shape>
    <shape type="rectangle"> <!-- floor -->
        <transform name="to_world"><rotate x="1" angle="-90"/><translate y="-1"/></transform>
        <ref id="white"/>
    </shape>
    <shape type="rectangle"> <!-- ceiling -->
        <transform name="to_world"><rotate x="1" angle="90"/><translate y="1"/></transform>
        <ref id="white"/>
    </shape>
    <shape type="rectangle"> <!-- back wall -->
        <transform name="to_world"><translate z="-1"/></transform>
        <ref id="white"/>
    </shape>
    <shape type="rectangle"> <!-- left wall -->
        <transform name="to_world"><rotate y="1" angle="90"/><translate x="-1"/></transform>
        <ref id="red"/>
    </shape>
    <shape type="rectangle"> <!-- right wall -->
        <transform name="to_world"><rotate y="1" angle="-90"/><translate x="1"/></transform>
        <ref id="green"/>
    </shape>

    <shape type="ply">
        <string name="filename" value="displaced_sphere.ply"/>
        <transform name="to_world">
            <scale value="0.55"/>
            <translate y="-0.38"/>
        </transform>
        <ref id="clay"/>
    </shape>
</scene>
)";

// -- the Cornell box, steady ------------------------------------------------------------------

/// scenes/cornell-box/scene.xml with the `path` integrator and an `hdrfilm`: the repository's
/// demo may render in time (transient_path into a transient film); this benchmark measures
/// `path`. Geometry, materials, lights, sensor, sampler and reconstruction filter are kept;
/// the integrator keeps the parameters `path` takes, the film its size and rfilter.
/// Returns the XML text and a note of what was changed.
std::pair<std::string, std::string> steady_cornell_xml(const std::string& file) {
    pugi::xml_document doc;
    const pugi::xml_parse_result parsed = doc.load_file(file.c_str());
    if (!parsed)
        throw femto::SceneError(
            fmt::format("{}: cannot read the scene: {}", file, parsed.description()));
    pugi::xml_node scene = doc.child("scene");
    pugi::xml_node integrator = scene.child("integrator");
    pugi::xml_node film = scene.child("sensor").child("film");
    if (!integrator || !film)
        throw femto::SceneError(file + ": expected <integrator> and <sensor><film> in <scene>");
    std::string note;
    auto keep_only = [](pugi::xml_node node, std::initializer_list<std::string_view> names,
                        bool keep_rfilter) {
        std::vector<pugi::xml_node> drop;
        for (pugi::xml_node c : node.children()) {
            if (c.type() != pugi::node_element) continue;
            const std::string_view name = c.attribute("name").value();
            const bool keep = (keep_rfilter && std::string_view(c.name()) == "rfilter") ||
                              std::find(names.begin(), names.end(), name) != names.end();
            if (!keep) drop.push_back(c);
        }
        for (pugi::xml_node c : drop) node.remove_child(c);
    };
    if (std::string_view(integrator.attribute("type").value()) != "path") {
        note += fmt::format("integrator {} -> path; ", integrator.attribute("type").value());
        integrator.attribute("type").set_value("path");
        keep_only(integrator, {"max_depth", "rr_depth", "hide_emitters"}, false);
    }
    if (std::string_view(film.attribute("type").value()) != "hdrfilm") {
        note += fmt::format("film {} -> hdrfilm; ", film.attribute("type").value());
        film.attribute("type").set_value("hdrfilm");
        keep_only(film, {"width", "height"}, true);
    }
    std::ostringstream out;
    doc.save(out, "    ");
    return {out.str(), note.empty() ? "used as is" : note.substr(0, note.size() - 2)};
}

// -- raw Embree ------------------------------------------------------------------------------

/// A ray as the benchmark stores it: 28 bytes, expanded into an RTCRayHit when traced (as
/// femto::Scene::intersect does with a femto::Ray).
struct CompactRay {
    Vec3 o, d;
    float tmax;
};

/// Embree's own scene for a femto scene's shapes, built by the host's femto::detail::EmbreeScene
/// (the construction femto::Scene uses: geometry, build quality, flags), plus the ray sets and
/// the timed raw tracing. It is a second BVH next to the renderer's, so that the diagnostic
/// `--raw-not-robust` can build it without RTC_SCENE_FLAG_ROBUST.
class RawScene {
public:
    RawScene(const femto::Scene& scene, bool robust) {
        const auto t0 = Clock::now();
        embree_ = std::make_unique<femto::detail::EmbreeScene>(scene.shapes(), robust);
        build_seconds_ = std::chrono::duration<double>(Clock::now() - t0).count();
        for (const femto::Shape* shape : embree_->shapes()) {
            if (!shape) continue;  // left out of the BVH (an invisible `null` surface)
            surfaces_.push_back(shape);
            if (shape->emitter()) lights_.push_back(shape);
        }
        if (surfaces_.empty())
            throw std::runtime_error("the scene has no visible surface to start raw rays from");
        surface_cdf_ = area_cdf(surfaces_);
        light_cdf_ = area_cdf(lights_);
    }
    size_t triangles() const { return embree_->triangles(); }
    size_t spheres() const { return embree_->spheres(); }
    double build_seconds() const { return build_seconds_; }
    bool has_lights() const { return !lights_.empty(); }

    /// Random incoherent rays: origin uniform by area over all surfaces, offset along the
    /// geometric normal like femto's Hit::spawn; direction uniform on the normal's hemisphere.
    std::vector<CompactRay> bounce_rays(size_t n, uint64_t seed) const {
        std::vector<CompactRay> rays(n);
        femto::Pcg32 rng(seed, 1);
        for (auto& r : rays) {
            const femto::ShapeSample s = sample_surface(surfaces_, surface_cdf_, rng);
            const Vec3 local =
                femto::warp::square_to_uniform_hemisphere({rng.next_float(), rng.next_float()});
            r.d = femto::Frame(s.n).to_world(local);
            r.o = femto::offset_origin(s.p, s.n, r.d, s.p_error);
            r.tmax = femto::kInfinity;
        }
        return rays;
    }

    /// Shadow rays: from the same kind of origins to a uniform point on an area light,
    /// stopping just short of it (femto's Hit::spawn_to).
    std::vector<CompactRay> shadow_rays(size_t n, uint64_t seed) const {
        std::vector<CompactRay> rays(n);
        femto::Pcg32 rng(seed, 2);
        for (auto& r : rays) {
            const femto::ShapeSample s = sample_surface(surfaces_, surface_cdf_, rng);
            const femto::ShapeSample l = sample_surface(lights_, light_cdf_, rng);
            r.o = femto::offset_origin(s.p, s.n, l.p - s.p, s.p_error);
            const Vec3 d = l.p - r.o;
            const float dist = femto::length(d);
            r.d = dist > 0 ? d / dist : s.n;
            r.tmax = femto::shadow_ray_length(dist, l.p);
        }
        return rays;
    }

    struct Result {
        uint64_t rays = 0, hits = 0;
        double seconds = 0;
        double cpu_seconds = 0;  ///< process CPU time (user + system) during the measurement
        double mrays_per_s() const { return seconds > 0 ? double(rays) / seconds * 1e-6 : 0; }
        double mrays_per_cpu_s() const {
            return cpu_seconds > 0 ? double(rays) / cpu_seconds * 1e-6 : 0;
        }
    };

    /// Traces `rays` in passes until `min_seconds` have elapsed (at least one pass), on at most
    /// `threads` threads. occluded: rtcOccluded1 instead of rtcIntersect1.
    Result trace(const std::vector<CompactRay>& rays, int threads, double min_seconds,
                 bool occluded) const {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        enable_flush_to_zero();
        std::atomic<uint64_t> hits{0};
        Result res;
        const double cpu0 = cpu_seconds();
        const auto t0 = Clock::now();
        do {
            tbb::parallel_for(tbb::blocked_range<size_t>(0, rays.size(), 1024),
                              [&](const tbb::blocked_range<size_t>& range) {
                                  enable_flush_to_zero();
                                  uint64_t local_hits = 0;
                                  RTCIntersectContext ctx;
                                  rtcInitIntersectContext(&ctx);
                                  for (size_t i = range.begin(); i != range.end(); ++i)
                                      local_hits += occluded ? trace_occluded(rays[i], ctx)
                                                             : trace_intersect(rays[i], ctx);
                                  hits.fetch_add(local_hits, std::memory_order_relaxed);
                              });
            res.rays += rays.size();
            res.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        } while (res.seconds < min_seconds);
        res.cpu_seconds = cpu_seconds() - cpu0;
        res.hits = hits.load();
        return res;
    }

private:
    static std::vector<float> area_cdf(const std::vector<const femto::Shape*>& shapes) {
        std::vector<float> cdf;
        double total = 0;
        for (const auto* s : shapes) cdf.push_back(float(total += s->surface_area()));
        for (float& c : cdf) c = float(c / total);
        if (!cdf.empty()) cdf.back() = 1.f;
        return cdf;
    }

    static femto::ShapeSample sample_surface(const std::vector<const femto::Shape*>& shapes,
                                             const std::vector<float>& cdf, femto::Pcg32& rng) {
        const float u = rng.next_float();
        const size_t i = std::min(size_t(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()),
                                  shapes.size() - 1);
        return shapes[i]->sample_area({rng.next_float(), rng.next_float()});
    }

    int trace_intersect(const CompactRay& r, RTCIntersectContext& ctx) const {
        RTCRayHit rh;
        femto::detail::init_rayhit(rh, r.o, r.d, 0.f, r.tmax);
        rtcIntersect1(embree_->get(), &ctx, &rh);
        return rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }

    int trace_occluded(const CompactRay& r, RTCIntersectContext& ctx) const {
        RTCRay ray;
        femto::detail::init_ray(ray, r.o, r.d, 0.f, r.tmax);
        rtcOccluded1(embree_->get(), &ctx, &ray);
        return ray.tfar < 0;
    }

    std::unique_ptr<femto::detail::EmbreeScene> embree_;
    std::vector<const femto::Shape*> surfaces_, lights_;
    std::vector<float> surface_cdf_, light_cdf_;
    double build_seconds_ = 0;  ///< the EmbreeScene's construction: buffers and BVH
};

/// Spreads the low 21 bits of x so that bit b moves to bit 3b.
uint64_t spread_bits(uint64_t x) {
    x &= 0x1fffffu;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
}

/// The same rays ordered along a Morton (Z-order) curve of their origins: directions stay
/// random, but consecutive rays start close together, as in a renderer tracing a tile.
std::vector<CompactRay> sorted_by_origin(std::vector<CompactRay> rays) {
    femto::Bounds3 b;
    for (const auto& r : rays) b.expand(r.o);
    std::vector<std::pair<uint64_t, uint32_t>> keys(rays.size());
    for (size_t i = 0; i < rays.size(); ++i) {
        uint64_t key = 0;
        for (int a = 0; a < 3; ++a) {
            const float extent = b.max[a] - b.min[a];
            const float t = extent > 0 ? (rays[i].o[a] - b.min[a]) / extent : 0.f;
            key |= spread_bits(uint64_t(femto::clamp(t, 0.f, 1.f) * 2097151.f)) << a;
        }
        keys[i] = {key, uint32_t(i)};
    }
    std::sort(keys.begin(), keys.end());
    std::vector<CompactRay> out(rays.size());
    for (size_t i = 0; i < keys.size(); ++i) out[i] = rays[keys[i].second];
    return out;
}

// -- the benchmark ---------------------------------------------------------------------------

struct RunRow {
    std::string scene;
    size_t triangles = 0;
    int threads = 0, run = 0;
    RawScene::Result raw, sorted, shadow;
    femto::RenderStats femto;
    double femto_cpu_seconds = 0;  ///< process CPU time around femto::render()
    double load = 0;
    double femto_mrays_per_s() const {
        return femto.seconds > 0 ? double(femto.rays) / femto.seconds * 1e-6 : 0;
    }
    double femto_mrays_per_cpu_s() const {
        return femto_cpu_seconds > 0 ? double(femto.rays) / femto_cpu_seconds * 1e-6 : 0;
    }
};

struct SummaryRow {
    std::string scene;
    size_t triangles = 0;
    int threads = 0, runs = 0;
    double raw_median = 0, raw_min = 0, raw_max = 0;
    double femto_median = 0, femto_min = 0, femto_max = 0;
    double shadow_median = 0, sorted_median = 0;
    double sorted_ratio = 0;  ///< femto median / raw sorted-origins median
    double ratio = 0;         ///< femto median / raw median
    double paired_ratio = 0;  ///< median over runs of femto/raw measured back to back
    double raw_cpu_median = 0, femto_cpu_median = 0;  ///< Mrays per CPU second
    double cpu_ratio = 0;                             ///< femto / raw, per CPU second
    double raw_cores = 0, femto_cores = 0;            ///< median CPU time / wall time
    double rays_per_sample = 0;
    std::string load_before, load_after;
};

struct BenchScene {
    std::string name;
    std::unique_ptr<femto::Scene> scene;
    uint32_t spp = 0;
    double load_seconds = 0;
};

BenchScene load_bench_scene(const std::string& name, const Options& opt, const fs::path& work) {
    femto::LoadOptions lo;
    lo.defines = {{"res", std::to_string(opt.res)}, {"max_depth", std::to_string(opt.max_depth)}};
    BenchScene b;
    b.name = name;
    const auto t0 = Clock::now();
    if (name == "cornell-box") {
        b.spp = opt.cornell_spp;
        lo.defines.emplace_back("spp", std::to_string(b.spp));
        const std::string dir = opt.source_dir + "/scenes/cornell-box";
        const auto [xml, note] = steady_cornell_xml(dir + "/scene.xml");
        fmt::print("{}/scene.xml: {}\n", dir, note);
        b.scene = femto::load_scene_string(xml, lo, dir);
    } else {
        b.spp = opt.sphere_spp;
        lo.defines.emplace_back("spp", std::to_string(b.spp));
        const size_t tris = write_displaced_sphere(work / "displaced_sphere.ply", opt.rings);
        {
            std::ofstream f(work / "scene.xml");
            f << kSphereSceneXml;
            if (!f) throw std::runtime_error("cannot write " + (work / "scene.xml").string());
        }
        fmt::print("wrote {} ({} triangles) and scene.xml\n",
                   (work / "displaced_sphere.ply").string(), tris);
        b.scene = femto::load_scene((work / "scene.xml").string(), lo);
    }
    b.load_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    return b;
}

femto::RenderStats render_once(femto::Scene& scene, int threads, uint32_t spp, uint64_t seed) {
    femto::RenderOptions ro;
    ro.threads = threads;
    ro.spp = spp;
    ro.seed = seed;
    return femto::render(scene, ro);
}

std::string csv_escape(const std::string& s) {
    if (s.find_first_of(",\"\n") == std::string::npos) return s;
    std::string out = "\"";
    for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
    return out + "\"";
}

/// The folder for the generated scene: `--work-dir`, or a new temporary folder that is
/// removed again (also when the benchmark fails) unless `--keep` was given.
class WorkDir {
public:
    explicit WorkDir(const Options& opt) : keep_(opt.keep_work) {
        if (!opt.work_dir.empty()) {
            path_ = opt.work_dir;
            fs::create_directories(path_);
            keep_ = true;
        } else {
            std::string tmpl = (fs::temp_directory_path() / "femto-bench-XXXXXX").string();
            if (!mkdtemp(tmpl.data())) throw std::runtime_error("cannot create a temporary folder");
            path_ = tmpl;
        }
    }
    ~WorkDir() {
        std::error_code ec;
        if (!keep_) fs::remove_all(path_, ec);
    }
    WorkDir(const WorkDir&) = delete;
    WorkDir& operator=(const WorkDir&) = delete;
    const fs::path& path() const { return path_; }
    bool kept() const { return keep_; }

private:
    fs::path path_;
    bool keep_;
};

int run(const Options& opt) {
    fs::create_directories(opt.out_dir);
    const WorkDir work_dir(opt);
    const fs::path& work = work_dir.path();

    const std::string load_start = read_loadavg();
    const std::string date = now_utc();
    const long cores = sysconf(_SC_NPROCESSORS_ONLN);
    fmt::print("femto_bench_rays: femto {}, Embree {}, {}\n", femto::version(), RTC_VERSION_STRING,
               FEMTO_BENCH_BUILD);
    fmt::print("machine: {} cores, {}; {}; load average {}\n", cores, cpu_model(), date,
               load_start);
    fmt::print(
        "runs {}, res {}x{}, spp cornell {} / sphere {}, max_depth {}, raw rays {} x >= {} s\n\n",
        opt.runs, opt.res, opt.res, opt.cornell_spp, opt.sphere_spp, opt.max_depth, opt.raw_rays,
        opt.raw_seconds);

    std::vector<RunRow> rows;
    std::vector<SummaryRow> summary;
    for (const std::string& name : opt.scenes) {
        BenchScene bs = load_bench_scene(name, opt, work);
        RawScene raw(*bs.scene, opt.raw_robust);
        const auto rays = raw.bounce_rays(opt.raw_rays, opt.seed);
        const auto sorted = sorted_by_origin(rays);
        const auto shadow =
            raw.has_lights() ? raw.shadow_rays(opt.raw_rays, opt.seed) : std::vector<CompactRay>{};
        fmt::print("{}: {} triangles, {} spheres; loaded in {:.2f} s, raw BVH built in {:.2f} s\n",
                   name, raw.triangles(), raw.spheres(), bs.load_seconds, raw.build_seconds());
        if (!opt.preview_dir.empty()) {  // on a scene of its own: the film starts empty
            fs::create_directories(opt.preview_dir);
            const BenchScene preview = load_bench_scene(name, opt, work);
            femto::RenderOptions ro;
            ro.spp = preview.spp;
            ro.seed = opt.seed;
            const femto::RenderStats st = femto::render(*preview.scene, ro);
            for (const auto& f : preview.scene->sensor().film().write(
                     (fs::path(opt.preview_dir) / name).string(),
                     femto::make_render_info(*preview.scene, ro, st)))
                fmt::print("  preview: {}\n", f);
        }

        for (int threads : opt.threads) {
            // Warm-up, not recorded: TBB workers, page faults, caches.
            raw.trace(rays, threads, 0.0, false);
            render_once(*bs.scene, threads, 1, opt.seed);

            const std::string load_before = read_loadavg();
            std::vector<double> raw_rates, femto_rates, shadow_rates, sorted_rates, paired,
                per_sample;
            std::vector<double> raw_cpu_rates, femto_cpu_rates, raw_cores, femto_cores;
            for (int r = 0; r < opt.runs; ++r) {
                RunRow row;
                row.scene = name;
                row.triangles = raw.triangles();
                row.threads = threads;
                row.run = r;
                row.load = load1();
                auto measure_raw = [&] {
                    row.raw = raw.trace(rays, threads, opt.raw_seconds, false);
                    if (!shadow.empty())
                        row.shadow = raw.trace(shadow, threads, 0.5 * opt.raw_seconds, true);
                    row.sorted = raw.trace(sorted, threads, 0.5 * opt.raw_seconds, false);
                };
                // ABBA: raw first on even runs, femto first on odd runs.
                if (r % 2 == 0) measure_raw();
                const double cpu0 = cpu_seconds();
                row.femto = render_once(*bs.scene, threads, bs.spp, opt.seed);
                row.femto_cpu_seconds = cpu_seconds() - cpu0;
                if (r % 2 == 1) measure_raw();

                raw_rates.push_back(row.raw.mrays_per_s());
                shadow_rates.push_back(row.shadow.mrays_per_s());
                sorted_rates.push_back(row.sorted.mrays_per_s());
                femto_rates.push_back(row.femto_mrays_per_s());
                paired.push_back(row.femto_mrays_per_s() / row.raw.mrays_per_s());
                per_sample.push_back(double(row.femto.rays) / double(row.femto.camera_samples));
                raw_cpu_rates.push_back(row.raw.mrays_per_cpu_s());
                femto_cpu_rates.push_back(row.femto_mrays_per_cpu_s());
                raw_cores.push_back(row.raw.cpu_seconds / row.raw.seconds);
                femto_cores.push_back(row.femto_cpu_seconds / row.femto.seconds);
                fmt::print(
                    "  {} threads, run {}: raw {:6.2f} Mray/s (hit {:4.1f}%), sorted {:6.2f}, "
                    "shadow "
                    "{:6.2f} Mray/s, femto {:6.2f} Mray/s ({:.2f} s, {:.2f} rays/sample); cores "
                    "used raw "
                    "{:.2f} femto {:.2f}; load {:.2f}\n",
                    threads, r, row.raw.mrays_per_s(),
                    100.0 * double(row.raw.hits) / double(std::max<uint64_t>(1, row.raw.rays)),
                    row.sorted.mrays_per_s(), row.shadow.mrays_per_s(), row.femto_mrays_per_s(),
                    row.femto.seconds, double(row.femto.rays) / double(row.femto.camera_samples),
                    raw_cores.back(), femto_cores.back(), row.load);
                std::fflush(stdout);
                rows.push_back(row);
            }
            SummaryRow s;
            s.scene = name;
            s.triangles = raw.triangles();
            s.threads = threads;
            s.runs = opt.runs;
            s.raw_median = median(raw_rates);
            s.raw_min = *std::min_element(raw_rates.begin(), raw_rates.end());
            s.raw_max = *std::max_element(raw_rates.begin(), raw_rates.end());
            s.femto_median = median(femto_rates);
            s.femto_min = *std::min_element(femto_rates.begin(), femto_rates.end());
            s.femto_max = *std::max_element(femto_rates.begin(), femto_rates.end());
            s.shadow_median = median(shadow_rates);
            s.sorted_median = median(sorted_rates);
            s.sorted_ratio = s.femto_median / s.sorted_median;
            s.ratio = s.femto_median / s.raw_median;
            s.paired_ratio = median(paired);
            s.rays_per_sample = median(per_sample);
            s.raw_cpu_median = median(raw_cpu_rates);
            s.femto_cpu_median = median(femto_cpu_rates);
            s.cpu_ratio = s.femto_cpu_median / s.raw_cpu_median;
            s.raw_cores = median(raw_cores);
            s.femto_cores = median(femto_cores);
            s.load_before = load_before;
            s.load_after = read_loadavg();
            summary.push_back(s);
        }
    }
    const std::string load_end = read_loadavg();

    // Table.
    fmt::print(
        "\n{:<16} {:>9} {:>3} | {:>6} {:>6} {:>6} {:>6} | {:>6} {:>6} | {:>6} | {:>6} {:>6} "
        "{:>6} | {:>5} {:>5}\n",
        "", "", "", "Mray/s", "", "femto/", "", "sorted", "femto/", "shadow", "Mray/", "CPU-s",
        "femto/", "cores", "");
    fmt::print(
        "{:<16} {:>9} {:>3} | {:>6} {:>6} {:>6} {:>6} | {:>6} {:>6} | {:>6} | {:>6} {:>6} "
        "{:>6} | {:>5} {:>5}\n",
        "scene", "triangles", "thr", "raw", "femto", "raw", "paired", "raw", "sorted", "raw", "raw",
        "femto", "raw", "raw", "femto");
    for (const auto& s : summary)
        fmt::print(
            "{:<16} {:>9} {:>3} | {:>6.2f} {:>6.2f} {:>6.3f} {:>6.3f} | {:>6.2f} {:>6.3f} | "
            "{:>6.2f} | {:>6.2f} {:>6.2f} {:>6.3f} | {:>5.2f} {:>5.2f}\n",
            s.scene, s.triangles, s.threads, s.raw_median, s.femto_median, s.ratio, s.paired_ratio,
            s.sorted_median, s.sorted_ratio, s.shadow_median, s.raw_cpu_median, s.femto_cpu_median,
            s.cpu_ratio, s.raw_cores, s.femto_cores);
    fmt::print(
        "Medians of {} runs. raw = rtcIntersect1 on random incoherent rays; femto/raw = ratio of "
        "the medians\n(goal >= 0.7); paired = median of the per-run ratios; sorted raw = the same "
        "rays ordered by origin\n(Morton); shadow raw = rtcOccluded1 to the lights; Mray/CPU-s = "
        "rays per second of process CPU time;\ncores = CPU time / wall time (below the thread "
        "count when other processes hold the cores).\n",
        opt.runs);
    fmt::print("load average: start {}, end {}\n", load_start, load_end);

    // CSV files.
    const fs::path out = opt.out_dir;
    {
        std::ofstream f(out / "rays.csv");
        f << "scene,triangles,threads,run,raw_mrays_per_s,femto_mrays_per_s,"
             "raw_shadow_mrays_per_s,raw_sorted_mrays_per_s,raw_rays,raw_seconds,raw_cpu_seconds,"
             "raw_hit_fraction,"
             "femto_rays,femto_seconds,femto_cpu_seconds,femto_spp,femto_rays_per_sample,load1\n";
        for (const auto& r : rows)
            f << fmt::format(
                "{},{},{},{},{:.4f},{:.4f},{:.4f},{:.4f},{},{:.6f},{:.6f},{:.4f},{},{:.6f},{:.6f},{"
                "},"
                "{:.4f},{:.2f}\n",
                r.scene, r.triangles, r.threads, r.run, r.raw.mrays_per_s(), r.femto_mrays_per_s(),
                r.shadow.mrays_per_s(), r.sorted.mrays_per_s(), r.raw.rays, r.raw.seconds,
                r.raw.cpu_seconds, double(r.raw.hits) / double(std::max<uint64_t>(1, r.raw.rays)),
                r.femto.rays, r.femto.seconds, r.femto_cpu_seconds, r.femto.spp_done,
                double(r.femto.rays) / double(r.femto.camera_samples), r.load);
        if (!f) throw std::runtime_error("cannot write " + (out / "rays.csv").string());
    }
    {
        std::ofstream f(out / "rays_summary.csv");
        f << "scene,triangles,threads,runs,raw_median_mrays_per_s,raw_min,raw_max,"
             "femto_median_mrays_per_s,femto_min,femto_max,ratio,paired_ratio,"
             "raw_shadow_median_mrays_per_s,raw_sorted_median_mrays_per_s,sorted_ratio,"
             "raw_median_mrays_per_cpu_s,"
             "femto_median_mrays_per_cpu_s,cpu_ratio,raw_cores_used,femto_cores_used,"
             "femto_rays_per_sample,load_before,load_after\n";
        for (const auto& s : summary)
            f << fmt::format(
                "{},{},{},{},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},"
                "{:.4f},{:.4f},{:.4f},{:.4f},{:.3f},{:.3f},{:.4f},{},{}\n",
                s.scene, s.triangles, s.threads, s.runs, s.raw_median, s.raw_min, s.raw_max,
                s.femto_median, s.femto_min, s.femto_max, s.ratio, s.paired_ratio, s.shadow_median,
                s.sorted_median, s.sorted_ratio, s.raw_cpu_median, s.femto_cpu_median, s.cpu_ratio,
                s.raw_cores, s.femto_cores, s.rays_per_sample, csv_escape(s.load_before),
                csv_escape(s.load_after));
        if (!f) throw std::runtime_error("cannot write " + (out / "rays_summary.csv").string());
    }
    {
        std::ofstream f(out / "rays_meta.txt");
        f << "date: " << date << "\n"
          << "nproc: " << cores << "\n"
          << "cpu: " << cpu_model() << "\n"
          << "load_start: " << load_start << "\n"
          << "load_end: " << load_end << "\n"
          << "femto: " << femto::version() << "\n"
          << "embree: " << RTC_VERSION_STRING << "\n"
          << "build: " << FEMTO_BENCH_BUILD << "\n"
          << "runs: " << opt.runs << "\n"
          << "res: " << opt.res << "\n"
          << "cornell_spp: " << opt.cornell_spp << "\n"
          << "sphere_spp: " << opt.sphere_spp << "\n"
          << "max_depth: " << opt.max_depth << "\n"
          << "raw_rays: " << opt.raw_rays << "\n"
          << "raw_seconds: " << opt.raw_seconds << "\n"
          << "seed: " << opt.seed << "\n"
          << "raw_scene_flags: " << (opt.raw_robust ? "robust" : "none") << "\n";
        if (!f) throw std::runtime_error("cannot write " + (out / "rays_meta.txt").string());
    }
    fmt::print("wrote {}, {}, {}\n", (out / "rays.csv").string(),
               (out / "rays_summary.csv").string(), (out / "rays_meta.txt").string());

    if (work_dir.kept()) fmt::print("generated scene kept in {}\n", work.string());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(parse_options(argc, argv));
    } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "femto_bench_rays: %s\n", e.what());
        return 2;
    } catch (const femto::SceneError& e) {
        std::fprintf(stderr, "femto_bench_rays: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "femto_bench_rays: error: %s\n", e.what());
        return 1;
    }
}
