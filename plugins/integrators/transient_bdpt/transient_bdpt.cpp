// transient_bdpt: bidirectional path tracing in time (thesis ch. 5.4: the transient path
// integral sampled with eye and light subpaths), surfaces and media, every contribution at its
// own time of flight. Veach's estimator as pbrt-v3 writes it: for each camera sample one camera
// subpath and one light subpath, then every strategy (s, t) that joins the first s light
// vertices to the first t camera vertices, weighted by the power (or balance) heuristic over
// all strategies that could have made the same path.
//
// Reading order:
//   - Vertex: what MIS and connections need of a subpath vertex (position, normal, material,
//     the medium the path was in, the densities of sampling it from either side);
//   - camera_subpath() / light_subpath(): random walks (mean-free-path distances in media,
//     BSDF and phase sampling, no Russian roulette: max_depth or the window ends them); a
//     camera vertex on an emitter adds the strategy s = 0 as soon as it is found;
//   - connect(): the strategies with s >= 1 and t >= 1: the light sample (s = 1), the sensor
//     connection (t = 1, a splat onto the film), and the general connection;
//   - place_and_connect(): the connection strategy's variants (below);
//   - mis_weight(): the heuristic over the path's strategies, from the vertices' densities:
//     local_weight() sums those near the connection (the usual case),
//     whole_path_weight() all of them (time-angular directions, placed vertices).
// Time: each camera vertex keeps its PathClock and each light vertex its LightClock; a joined
// path's time is the light subpath's, plus the connection's optical length, plus the camera
// subpath's (femto/path_clock.h). The window is checked before a connection's shadow ray.
// Time sampling (ch. 5.6): the nested <distance> strategy (exponential, alone or MIS-combined
// with mean free paths) draws the distances of both subpaths, and its densities are in the MIS
// weights (unlike pbrt-v3's volumetric BDPT): a segment's density from either end is that of
// the walk stopping at, or passing through to, its far end (SegmentDensities), so the weights
// favour the strategy whose distances fit the time window. The nested <connection> strategy
// (line_to_point, equiangular; Fig. 5.6 middle) adds a variant of each strategy (s, t >= 2):
// its last camera vertex placed on the camera subpath's ray toward light vertex s - 1 instead
// of by a distance, on the ray's first piece if that lies in a medium; MIS weighs every variant
// of every strategy (placement_factor()). The nested <angular> strategy (time: ch. 5.6.3)
// chooses directions out of medium vertices with the next distance drawn first: light subpaths
// aim at the camera, camera subpaths at the light subpath's first vertex (so the light subpath
// is traced first). Its density depends on that distance, which the path shows only when the
// next vertex is in the medium; the weights take the density at the segment's own length
// everywhere (angular_densities()), the exact one where the next vertex is a medium vertex and
// a deterministic stand-in elsewhere, which keeps them a partition of unity.
// Delta lights: a point or spot light is never hit (no s = 0); a collimated beam (and a
// directional light) is never hit either, and its vertex's position density moves to the next
// vertex (pdf_light()). Environments (constant, envmap) are light vertices of a direction
// (pbrt-v3's infinite lights): their densities are the direction's, the next vertex takes the
// start disk's area density, a camera subpath that leaves the scene adds s = 0
// (environment_hit()), and the light vertex never joins the camera directly.
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "femto/image_io.h"
#include "femto/integrator.h"
#include "femto/log.h"
#include "femto/mis.h"
#include "femto/path_clock.h"
#include "femto/plugin.h"
#include "femto/sensor.h"
#include "femto/time_sampling.h"
#include "femto/transport.h"

namespace {

using namespace femto;

// A vertex of a camera or light subpath.
struct Vertex {
    enum class Kind : uint8_t { Camera, Light, Surface, Medium };
    Kind kind = Kind::Surface;
    Vec3 p;
    Vec3 n;   // geometric normal of surface and area-light vertices; zero otherwise
    Vec3 wi;  // unit direction back to the previous vertex of its own subpath (zero at the ends)
    Hit hit;  // surface vertices (others leave it stale: see reuse())
    const Bsdf* bsdf = nullptr;            // surface vertices
    const PhaseFunction* phase = nullptr;  // medium vertices
    const Emitter* emitter = nullptr;      // light vertices; surface vertices on an emitter
    EmissionSample emission;               // light vertices
    MediumTracker medium;                  // the medium the path was in when it arrived
    VertexEvent event;  // light subpaths: the material's event (light leaving carries it)
    // Densities of sampling this vertex from its subpath's previous vertex (fwd) and from the
    // next one (rev): area measure at surfaces, volume in media, per unit of area-light area.
    double pdf_fwd = 0, pdf_rev = 0;
    // The distance densities of the segment from the previous vertex of its subpath to this
    // one: of reaching this vertex walking from there (fwd), and of reaching there walking back
    // from here (rev) (SegmentDensities; 1 in vacuum).
    double segment_fwd = 1, segment_rev = 1;
    double segment_optical = 0;          // its optical length
    bool segment_single_medium = false;  // it lies in one medium, with no boundary on it
    bool delta = false;                  // scattered by a delta lobe: no connection can use it
    bool smooth = false;  // surface vertices: the BSDF has a smooth lobe (connectible() asks)
    // A light vertex of an environment (constant, envmap): light from direction -n, from the
    // start plane of its plane wave (SceneSphere). Its densities are those of a direction,
    // and the next vertex takes the start disk's area density (pdf_light()).
    bool environment = false;
    // The segment back to the previous vertex of its subpath, as to_area() and towards() find
    // it from here (back_of()). Every connection at this vertex asks for the density of
    // sampling that vertex from here (mis_weight()); kept, it is found once per vertex instead
    // of once per connection, and not at all at vertices no connection uses (delta lobes).
    struct Back {
        bool valid = false;
        bool direction_only = false;   // the previous vertex is an environment's
        Vec3 dir;                      // towards(*this, previous)
        double d2 = 0;                 // squared distance
        double cos_over_distance = 1;  // |cos| at the previous vertex over the distance (surface)
        // to_area(pdf_dir, *this, previous).
        double to_area(double pdf_dir) const {
            if (direction_only) return pdf_dir;
            if (!(d2 > 0)) return 0;
            return pdf_dir / d2 * cos_over_distance;
        }
    };
    mutable Back back;  // a cache: filled on first use

    // Makes a vertex of an earlier sample a fresh one, as `Vertex()` would but without zeroing
    // `hit` (216 bytes): a surface vertex's hit comes from Scene::intersect(), which sets all of
    // it, and no other vertex reads it. A new field must be reset here too.
    void reuse() {
        kind = Kind::Surface;
        p = n = wi = Vec3();
        bsdf = nullptr;
        phase = nullptr;
        emitter = nullptr;
        emission = EmissionSample();
        medium = MediumTracker();
        event = VertexEvent();
        pdf_fwd = pdf_rev = 0;
        segment_fwd = segment_rev = 1;
        segment_optical = 0;
        segment_single_medium = delta = smooth = environment = false;
        back.valid = false;
    }

    bool on_surface() const {
        return kind == Kind::Surface || (kind == Kind::Light && n != Vec3());
    }
    // A connection can end here (not a specular vertex).
    bool connectible() const {
        switch (kind) {
            case Kind::Surface:
                return smooth;
            case Kind::Light:
                return !emission.delta_direction;
            default:
                return true;
        }
    }
};

// A subpath's vertices. Its storage lasts from sample to sample (Subpaths is one per thread),
// and add() makes a new vertex of one an earlier sample left (Vertex::reuse()): building each
// ~450-byte vertex from zero, and copying the first in, took ~5 % of a BDPT render (perf).
class VertexList {
public:
    size_t size() const { return size_; }
    bool empty() const { return size_ == 0; }
    Vertex& operator[](size_t i) { return store_[i]; }
    const Vertex& operator[](size_t i) const { return store_[i]; }
    Vertex& back() { return store_[size_ - 1]; }
    const Vertex& back() const { return store_[size_ - 1]; }
    // A fresh vertex at the end (references to the others may move, as with std::vector).
    Vertex& add() {
        if (size_ == store_.size())
            store_.emplace_back();
        else
            store_[size_].reuse();
        return store_[size_++];
    }
    void pop_back() { --size_; }
    void clear() { size_ = 0; }

private:
    std::vector<Vertex> store_;
    size_t size_ = 0;
};

// A camera subpath with the weight and clock of each vertex, and a light subpath with the light
// arriving at each vertex and its clock. Reused across samples (one per thread).
struct Subpaths {
    VertexList camera, light;
    // A light sample's or a sensor sample's end vertex, for the MIS weight of its connection.
    mutable Vertex connection_end;
    std::vector<Throughput> camera_beta;  // weight of light arriving, the vertex's event included
    std::vector<PathClock> camera_clock;  // after the vertex's delay
    std::vector<Color> light_power;       // light arriving (before the vertex's event and BSDF)
    std::vector<LightClock> light_clock;  // after the vertex's delay
    // The ray each camera vertex's walk left along, on which connection strategies place
    // vertices (camera_out[j] leaves camera[j]); empty without a connection strategy.
    struct Outgoing {
        Ray ray;
        double pdf_dir;        // its direction's density (solid angle)
        double first_end;      // where its first piece ends (the first surface it meets)
        MediumTracker medium;  // the medium of that piece
        Throughput beta;       // the camera path's weight along it
    };
    std::vector<Outgoing> camera_out;
    // The segment densities of each connection in turn (Bdpt::fresh_segment()): one object a
    // sample keeps its distance strategy (SegmentDensities::mixture()) from one to the next.
    mutable SegmentDensities connection_segment{nullptr, false, DistanceContext{}};
    double emission_time = 0;  // the light subpath's
    // Bdpt::far_sums(): per subpath vertex, the MIS sum of the strategies joining the subpath
    // at or before it, filled as connections ask for them.
    mutable std::vector<double> light_far, camera_far;
    void clear() {
        camera.clear(), light.clear(), camera_beta.clear(), camera_clock.clear();
        light_power.clear(), light_clock.clear(), camera_out.clear();
        light_far.clear(), camera_far.clear();
    }
};

// Where a sample's decisions start in the sampler's dimensions (Sampler::advance_to). Drawn in
// sequence, a decision's dimension would depend on how many numbers the subpaths before it
// took: the second subpath's start and every connection's numbers would land on another
// dimension in each sample, and a low-discrepancy sampler could not stratify them
// (bench/README.md measures what that cost). So each subpath vertex and each connection starts
// at a dimension of its own: one that draws more than kStride numbers pushes the later ones
// along, never back onto a dimension already drawn.
struct DimensionLayout {
    static constexpr uint64_t kStride = 8;  // a vertex draws at most ~5 (distance, event, lobe)
    uint64_t camera = 0, light = 0, connections = 0, placed = 0;
    uint64_t light_vertex_count = 0;  // the most a light subpath has

    // `base`: the first dimension after the camera ray's; the subpath traced first comes first.
    DimensionLayout(uint64_t base, int camera_vertices, int light_vertices, bool camera_first)
        : light_vertex_count(uint64_t(light_vertices)) {
        const uint64_t camera_size = uint64_t(camera_vertices) * kStride;
        const uint64_t light_size = light_vertex_count * kStride;
        camera = camera_first ? base : base + light_size;
        light = camera_first ? base + camera_size : base;
        connections = base + camera_size + light_size;
        placed = connections + uint64_t(camera_vertices) * light_size;
    }
    // Vertex `index` of a subpath whose block starts at `subpath`.
    static uint64_t vertex(uint64_t subpath, size_t index) { return subpath + index * kStride; }
    // Strategy (s, t), and the placed variant joining light vertex s - 1 on camera_out[j].
    uint64_t connection(int s, int t) const {
        return connections + (uint64_t(t - 1) * light_vertex_count + uint64_t(s - 1)) * kStride;
    }
    uint64_t placement(size_t j, int s) const {
        return placed + (uint64_t(j) * light_vertex_count + uint64_t(s - 1)) * kStride;
    }
};

// The calling thread's subpaths, reused from sample to sample. Reached through a call that is
// never inlined: given the thread_local itself, GCC specialised the helpers it is passed to
// for it, and in a plugin (a shared library) every access there called __tls_get_addr (98
// calls in the library, ~1.3 % of a BDPT render's time).
[[gnu::noinline]] Subpaths& thread_subpaths() {
    thread_local Subpaths paths;
    return paths;
}

// pdf_dir (solid angle at `from`) as a density of `to`: area measure on a surface, volume
// measure in a medium.
double to_area(double pdf_dir, const Vertex& from, const Vertex& to) {
    if (to.environment) return pdf_dir;  // a direction toward an environment stays one
    const Vec3 d = to.p - from.p;
    const double d2 = double(squared_length(d));
    if (!(d2 > 0)) return 0;
    double pdf = pdf_dir / d2;
    if (to.on_surface()) pdf *= double(std::abs(dot(to.n, d))) / std::sqrt(d2);
    return pdf;
}

// The segment from v back to `prev`, the vertex before it on its subpath: what to_area(pdf, v,
// prev) and towards(v, prev) compute, to the same bits, kept in v on first use.
const Vertex::Back& back_of(const Vertex& v, const Vertex& prev) {
    Vertex::Back& back = v.back;
    if (back.valid) return back;
    back.valid = true;
    back.direction_only = prev.environment;
    const Vec3 d = prev.p - v.p;
    back.dir = normalize(d);
    back.d2 = double(squared_length(d));
    back.cos_over_distance =
        prev.on_surface() ? double(std::abs(dot(prev.n, d))) / std::sqrt(back.d2) : 1.0;
    return back;
}

// What a strategy's own connection adds to the path, for its MIS weight: the joining segment's
// distance densities (which neither subpath sampled but other strategies of the same path do:
// of reaching its light end walking from its camera end, and the reverse; 1 in vacuum), its
// optical length and whether it lies in one medium, and the whole path's optical length and
// delays (its time without the emission time).
struct Join {
    double at_light_end = 1, at_camera_end = 1;
    double optical = 0;
    bool single_medium = false;
    double path_time = 0;
    const Vec3* across = nullptr;  // towards(its camera end, its light end), where known
};

// Direction from a to b (inlined: GCC kept it a call, ~1 % of a BDPT render in perf).
[[gnu::always_inline]] inline Vec3 towards(const Vertex& a, const Vertex& b) {
    return normalize(b.p - a.p);
}

class Bdpt : public MonteCarloIntegrator {
public:
    Bdpt(const Properties& props, int64_t default_rr_depth)
        : MonteCarloIntegrator(props, default_rr_depth) {
        if (max_depth() == 0) props.fail("max_depth", "BDPT needs max_depth >= 1 (or -1)");
        light_image_ = props.get_bool("light_image", true);
        if (!props.get_bool("sample_direct", true))
            log_note(props.location_of("sample_direct"),
                     "femto's BDPT always samples the emitters and the sensor directly for the "
                     "strategies s = 1 and t = 1 (sample_direct=false is ignored)");
        const std::string heuristic = props.get_string("heuristic", "power");
        if (heuristic != "power" && heuristic != "balance")
            props.fail("heuristic",
                       "heuristic must be power or balance, not \"" + heuristic + "\"");
        power_ = heuristic == "power";
        only_s_ = int(props.get_int("strategy_s", -1));
        only_t_ = int(props.get_int("strategy_t", -1));
        if ((only_s_ < 0) != (only_t_ < 0) || only_s_ < -1 || only_t_ == 0 || only_t_ < -1)
            props.fail("strategy_s",
                       "strategy_s >= 0 and strategy_t >= 1 go together (or both "
                       "-1: every strategy, weighted by MIS)");
        images_.enabled = props.get_bool("strategy_images", false);
        images_location_ = props.location_of("strategy_images");
        only_length_ = int(props.get_int("path_length", -1));
        if (only_length_ == 0 || only_length_ < -1)
            props.fail("path_length", "path_length must be >= 1 (segments), or -1 for all");
        // Distances in media on both subpaths by the nested <distance> strategy (alone, or
        // MIS-combined with mean-free-path sampling).
        distance_ = std::static_pointer_cast<DistanceSampler>(
            props.child(PluginKind::Distance, "mean_free_path"));
        mis_ = props.get_bool("mis", false);
        // Connection strategies place vertices on the camera subpath's rays (place_and_connect).
        connection_ = std::static_pointer_cast<ConnectionSampler>(
            props.child(PluginKind::Connection, "deterministic"));
        connecting_ = connection_->places_vertex();
        only_placed_ = props.get_bool("strategy_placed", false);
        if (only_placed_ && (only_s_ < 1 || only_t_ < 2 || !connecting_))
            props.fail("strategy_placed",
                       "strategy_placed renders the connection strategy's variant of (strategy_s, "
                       "strategy_t) alone: it needs strategy_s >= 1 and strategy_t >= 2 (a placed "
                       "vertex joins a light vertex to a camera ray) and a <connection> strategy "
                       "that places vertices (line_to_point or equiangular)");
        // Directions out of medium vertices on both subpaths by the nested <angular> strategy.
        angular_ =
            std::static_pointer_cast<AngularSampler>(props.child(PluginKind::Angular, "phase"));
        steady_angular_ = angular_->steady();
    }

    // Strategies t = 1 splat; without them (an orthographic sensor) every contribution is the
    // camera sample's own (asked after preprocess()).
    bool splats() const override { return to_sensor_; }

    void preprocess(const Scene& scene) override {
        MonteCarloIntegrator::preprocess(scene);
        // A sensor no connection can reach (orthographic) leaves out the strategies t = 1, and
        // so does light_image=false. So does a sensor with area (an irradiance meter): the MIS
        // weights below take the sensor for one point.
        to_sensor_ = light_image_ && scene.sensor().connectable() && !scene.sensor().has_area();
        window_end_ = scene.time_window().end;
        if (images_.enabled) {
            if (max_depth() < 0)
                throw SceneError(images_location_,
                                 "strategy_images needs a finite max_depth (one image per (s, t) "
                                 "with s + t - 1 <= max_depth)");
            const Film& film = scene.sensor().film();
            images_.prepare(film.width(), film.height(), int(max_depth()),
                            scene.sensor().ray_weight());
        }
        distance_->prepare({window_end_});
        starts_.prepare(scene, type_name());
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& ray,
                ContributionList& out) const override {
        Subpaths& paths = thread_subpaths();
        paths.clear();
        paths.connection_segment = segment_densities();  // this integrator's strategy
        const DimensionLayout dims(sampler.dimension(), max_vertices(true), max_vertices(false),
                                   steady_angular_);
        if (steady_angular_) {
            camera_subpath(scene, sampler, ray, out, paths, dims.camera);
            light_subpath(scene, sampler, paths, ray.o, dims.light);
        } else {  // the camera subpath aims at the light subpath's first vertex
            light_subpath(scene, sampler, paths, ray.o, dims.light);
            camera_subpath(scene, sampler, ray, out, paths, dims.camera);
        }
        const int nc = int(paths.camera.size()), nl = int(paths.light.size());
        for (int t = to_sensor_ ? 1 : 2; t <= nc; ++t)
            for (int s = 1; s <= nl; ++s) {
                if (max_depth() >= 0 && s + t - 1 > max_depth()) break;
                // Light vertices only get later along their subpath: the rest are late too.
                if (too_late(paths, s, t)) break;
                if (!wanted(s, t)) continue;
                sampler.advance_to(dims.connection(s, t));
                connect(scene, sampler, paths, s, t, out);
            }
        if (connecting_) place_and_connect(scene, sampler, paths, dims, out);
    }

    // A distributed render adds every process's strategy images (atomics of doubles: the
    // reduction runs after the threads are done).
    std::vector<Accumulator> accumulators() override {
        static_assert(sizeof(std::atomic<double>) == sizeof(double));
        if (!images_.enabled) return {};
        return {Accumulator::of_doubles(reinterpret_cast<double*>(images_.sums.data()),
                                        images_.sums.size())};
    }

    // strategy_images: one steady EXR per strategy (docs/outputs.md).
    std::vector<std::string> write(const std::string& out_base,
                                   const RenderInfo& info) const override {
        if (!images_.enabled || info.samples_per_pixel == 0) return {};
        io::OutputSet files;
        const size_t pixels = size_t(images_.width) * size_t(images_.height);
        std::vector<float> rgb(pixels * 3);
        for (int s = 0; s <= images_.depth; ++s)
            for (int t = 1; s + t - 1 <= images_.depth; ++t) {
                const size_t o = images_.offset(s, t);
                double total = 0;
                for (size_t i = 0; i < pixels * 3; ++i) {
                    rgb[i] = float(images_.sums[o + i].load() / info.samples_per_pixel);
                    total += rgb[i];
                }
                if (!(total > 0)) continue;
                const std::string name = fmt::format("{}_bdpt_s{}_t{}.exr", out_base, s, t);
                io::write_exr_rgb(files.add(name), images_.width, images_.height, rgb.data(),
                                  {{"femto:strategy", fmt::format("s={} t={}", s, t)}});
            }
        return files.commit();
    }

private:
    // Whether strategy (s, t) is rendered (all, unless a debugging parameter picks some).
    // `placed`: the connection strategy's variant of (s, t).
    bool wanted(int s, int t, bool placed = false) const {
        const bool chosen = only_s_ < 0 || (s == only_s_ && t == only_t_ && placed == only_placed_);
        return chosen && (only_length_ < 0 || s + t - 1 == only_length_);
    }
    // Debugging: one strategy alone, unweighted.
    bool unweighted() const { return only_s_ >= 0; }
    // True when light vertex s - 1 reaches camera vertex t - 1 too late for the film's window
    // even over a connection of length zero: skipped before connect() touches the vertices, the
    // sampler or a square root. With unbounded depth many (s, t) pairs of long subpaths are such
    // (fog-object: 39 % of the calls to connect()). s = 1 with t >= 2 is a fresh light sample,
    // checked in light_sample().
    static bool too_late(const Subpaths& paths, int s, int t) {
        if (s == 1 && t >= 2) return false;
        const LightClock& light = paths.light_clock[size_t(s) - 1];
        return t == 1 ? !light.arrives_in_time(0.0)
                      : !paths.camera_clock[size_t(t) - 1].arrives_in_time(light, 0.0);
    }

    int max_vertices(bool camera) const {
        constexpr int kCap = 1024;  // unbounded paths: the window ends them long before
        if (max_depth() < 0) return kCap;
        return int(std::min<int64_t>(kCap, camera ? max_depth() + 1 : max_depth()));
    }

    // ---- subpaths ----------------------------------------------------------------------------

    // The camera subpath: the camera, then the scattering vertices the camera ray's path meets.
    // A vertex on an emitter adds the strategy s = 0 at once.
    // `dims`: its block of sampler dimensions (DimensionLayout).
    void camera_subpath(const Scene& scene, Sampler& sampler, const Ray& camera_ray,
                        ContributionList& out, Subpaths& paths, uint64_t dims) const {
        Walk walk{camera_ray, MediumTracker::at_sensor(scene), 0.0, segment_densities()};
        if (!paths.light.empty()) walk.has_target = true, walk.target = paths.light[0].p;
        Vertex& cam = paths.camera.add();
        cam.kind = Vertex::Kind::Camera;
        cam.p = camera_ray.o;
        cam.pdf_fwd = 1.f;
        cam.medium = walk.medium;
        // The camera vertex's weight and clock are made in place, not copied from the walk's
        // just-built ones (a copy read them back before their stores had landed: perf put
        // ~0.4 % of the render on it).
        PathClock clock(scene, out, camera_ray.o);
        Throughput beta;
        paths.camera_beta.emplace_back();
        paths.camera_clock.emplace_back(scene, out, camera_ray.o);
        walk.pdf_dir = scene.sensor().pdf_direction(camera_ray.d);
        // The rays out of camera vertices serve the connection strategy only (a 128-byte copy
        // per vertex, 1-2 % of a render without it). `paths` is thread_local and outlives the
        // sample: keep no pointer to the renderer's differential (the walk's own copy finds
        // the footprint of the first hit).
        if (connecting_) {
            Ray first_ray = walk.ray;
            first_ray.differential = nullptr;
            paths.camera_out.push_back({first_ray, walk.pdf_dir, kInfinity, walk.medium, beta});
        }
        while (int(paths.camera.size()) < max_vertices(true)) {
            sampler.advance_to(DimensionLayout::vertex(dims, paths.camera.size() - 1));
            // The vertex is built in place and taken back where the walk ends before it.
            Vertex& v = paths.camera.add();
            const Vertex& prev = paths.camera[paths.camera.size() - 2];
            Color weight(1.f);
            const double before = clock.time();
            const bool found =
                next_vertex(scene, sampler, walk, v, weight, [&](const Vec3& p, double eta) {
                    clock.travel_to(p, eta);
                    return !clock.expired();
                });
            if (connecting_) paths.camera_out.back().first_end = walk.first_end;
            if (!found) {
                paths.camera.pop_back();
                if (walk.escaped) environment_hit(scene, sampler, walk, paths, beta, clock, out);
                return;
            }
            v.segment_optical = clock.time() - before;
            beta *= weight;
            // A vertex on top of the previous one (a distance that rounds to 0) has no direction
            // to or from it: the walk ends (an event of probability zero in exact arithmetic).
            if (beta.is_black() || !(squared_length(v.p - prev.p) > 0.f)) {
                paths.camera.pop_back();
                return;
            }
            if (v.kind == Vertex::Kind::Surface || v.kind == Vertex::Kind::Medium)
                clock.reach_vertex();
            set_forward_density(walk, prev, v);
            if (v.emitter) emitter_hit(scene, sampler, paths, beta, clock, out);
            if (v.bsdf) apply_vertex_event(*v.bsdf, v.hit, sampler, clock, beta);
            paths.camera_beta.push_back(beta);
            paths.camera_clock.push_back(clock);
            if (int(paths.camera.size()) == max_vertices(true)) return;
            Color scatter;
            if (!scatter_from(sampler, walk, paths.camera, false, scatter)) return;
            beta *= scatter;
            if (!survives_roulette(int(paths.camera.size()) - 1, beta.max_gain(), sampler, beta))
                return;
            if (connecting_)
                paths.camera_out.push_back({walk.ray, walk.pdf_dir, kInfinity, walk.medium, beta});
        }
    }

    // The light subpath: a point on an emitter, then the scattering vertices its light meets.
    // Time-angular directions aim at `camera` (the camera sample's ray origin).
    void light_subpath(const Scene& scene, Sampler& sampler, Subpaths& paths, const Vec3& camera,
                       uint64_t dims) const {
        const int limit = max_vertices(false);
        if (limit < 1) return;
        sampler.advance_to(dims);
        const LightPathStarts::Start start = LightPathStarts::sample(scene, sampler);
        if (!start) return;
        const Emitter* emitter = start.emitter;
        const EmissionSample& es = start.emission;
        Vertex& light = paths.light.add();
        light.kind = Vertex::Kind::Light;
        light.p = es.p;
        light.n = es.n;
        light.emitter = emitter;
        light.emission = es;
        light.environment = emitter->is_infinite() && !emitter->is_delta();
        light.pdf_fwd = pdf_light_origin(scene, light);
        // A single ray (an infinitely thin collimated beam): no strategy can connect to its
        // start, so those that would (s = 1) leave the MIS weights, as a delta lobe's do.
        light.delta = es.delta_position && es.delta_direction;
        light.medium = starts_.medium(*emitter, es, es.d);
        LightClock clock(scene, *emitter, es.p, sampler);
        paths.emission_time = clock.time();
        if (clock.expired()) return paths.light.pop_back();
        paths.light_power.push_back(start.power());  // unused for the light vertex itself
        paths.light_clock.push_back(clock);
        Walk walk{emission_ray(es), light.medium, 0.0, segment_densities()};
        walk.pdf_dir = es.pdf_direction;
        walk.has_target = true;
        walk.target = camera;
        Color power = start.power();
        while (int(paths.light.size()) < limit) {
            sampler.advance_to(DimensionLayout::vertex(dims, paths.light.size()));
            Vertex& v = paths.light.add();  // in place, as on the camera subpath
            const Vertex& prev = paths.light[paths.light.size() - 2];
            Color weight(1.f);
            const double before = clock.time();
            if (!next_vertex(scene, sampler, walk, v, weight, [&](const Vec3& p, double eta) {
                    clock.travel_to(p, eta);
                    return !clock.expired();
                })) {
                paths.light.pop_back();
                return;
            }
            v.segment_optical = clock.time() - before;
            power *= weight;
            if (power.is_black() || !(squared_length(v.p - prev.p) > 0.f)) {
                paths.light.pop_back();
                return;
            }
            set_forward_density(walk, prev, v);
            if (v.bsdf) v.event = apply_vertex_event(*v.bsdf, v.hit, sampler, clock);
            paths.light_power.push_back(power);
            paths.light_clock.push_back(clock);
            if (int(paths.light.size()) == limit) return;
            Color scatter;
            if (!scatter_from(sampler, walk, paths.light, true, scatter)) return;
            power = leaving(paths.light.back().event, scatter * power);
            const float gain = power.max_component() / start.power().max_component();
            if (!survives_roulette(int(paths.light.size()) - 1, gain, sampler, power)) return;
        }
    }

    // Russian roulette (rr_depth > 0) after a subpath's `segments` segments: the walk goes on
    // with probability min(gain, 0.95) and its weight grows by its inverse. The MIS weights
    // leave it out (they need only be the same for every strategy of a path).
    template <typename Weight>
    bool survives_roulette(int segments, float gain, Sampler& sampler, Weight& weight) const {
        const float survived = roulette(segments, gain, sampler);
        weight *= Color(survived);
        return survived > 0.f;
    }

    // A random walk's state between vertices.
    struct Walk {
        Ray ray;
        MediumTracker medium;
        double pdf_dir = 0;            // density of ray.d at the walk's last vertex
        SegmentDensities segment;      // the media of the segment being walked
        double first_end = kInfinity;  // where the ray's first piece ends (its first surface)
        bool escaped = false;          // the walk left the scene in vacuum
        // Time-angular sampling: the point the walk aims at, and the next distance's uniform
        // number when drawn before the direction (-1 when not).
        bool has_target = false;
        Vec3 target = Vec3();
        double next_u = -1.0;
    };
    SegmentDensities segment_densities() const {
        return SegmentDensities(distance_.get(), mis_, DistanceContext{window_end_});
    }
    // Subpaths::connection_segment, emptied for a new connection.
    static SegmentDensities& fresh_segment(const Subpaths& paths) {
        paths.connection_segment.clear();
        return paths.connection_segment;
    }

    // The density of the walk reaching v from prev (direction and distance), and of the
    // segment walked back.
    static void set_forward_density(const Walk& walk, const Vertex& prev, Vertex& v) {
        v.segment_fwd = walk.segment.forward(v.kind == Vertex::Kind::Medium);
        v.segment_rev = walk.segment.backward(prev.kind == Vertex::Kind::Medium);
        v.segment_single_medium = walk.segment.single_medium();
        const double direction =
            prev.kind == Vertex::Kind::Light ? pdf_light(prev, v) : to_area(walk.pdf_dir, prev, v);
        v.pdf_fwd = direction * v.segment_fwd;
    }

    // The next scattering vertex along walk.ray: a medium vertex (mean-free-path distances) or
    // a surface that is not `null` (null boundaries are crossed). `travel(p, eta)` moves the
    // subpath's clock there and returns false when the path expired; `weight` gets the
    // segment's transmittance weight. Returns false when the walk ends.
    template <typename Travel>
    bool next_vertex(const Scene& scene, Sampler& sampler, Walk& walk, Vertex& v, Color& weight,
                     Travel&& travel) const {
        walk.segment.clear();
        Hit& hit = v.hit;  // found in place: a surface vertex keeps it
        for (int crossings = 0; crossings < 256; ++crossings) {
            const bool found = scene.intersect(walk.ray, hit);
            if (crossings == 0) walk.first_end = found ? double(hit.t) : kInfinity;
            if (const Medium* medium = walk.medium.medium) {
                const DistanceMixture& strategy = walk.segment.mixture(*medium);
                const double tmax = found ? double(hit.t) : kInfinity;
                const double u = walk.next_u >= 0 ? walk.next_u : double(sampler.next_1d());
                walk.next_u = -1.0;
                const DistanceSample ds =
                    sample_distance(*medium, walk.ray, tmax, strategy, u, sampler);
                // (A ray that leaves to infinity ends the walk: its piece's densities go unread.)
                walk.segment.add(ds.at.survival, ds.at.pdf);
                weight *= ds.weight;
                if (ds.scattered) {  // v.hit (the surface beyond) stays: only surfaces read it
                    v.kind = Vertex::Kind::Medium;
                    v.p = walk.ray.at(float(ds.distance));
                    v.wi = -walk.ray.d;
                    v.phase = &medium->phase();
                    v.medium = walk.medium;
                    return travel(v.p, medium->eta()) && !weight.is_black();
                }
                if (!found || weight.is_black()) return false;
            } else {
                walk.segment.add_vacuum();
                walk.escaped = !found;
            }
            if (!found || !travel(hit.p, walk.medium.eta())) return false;
            const Bsdf& bsdf = *hit.shape->bsdf();
            if (bsdf.is_null()) {
                walk.medium.cross(hit, walk.ray.d);
                walk.ray = hit.spawn(walk.ray.d);
                if (hit.shape->emitter()) continue;  // a visible null emitter is not a vertex
                continue;
            }
            v.kind = Vertex::Kind::Surface;
            v.p = hit.p;
            v.wi = -walk.ray.d;
            v.n = hit.ng;
            v.bsdf = &bsdf;
            v.smooth = (bsdf.flags() & kBsdfSmooth) != 0;  // once: connections ask again and again
            v.emitter = hit.shape->emitter();
            v.medium = walk.medium;
            return true;
        }
        return false;
    }

    // Samples the direction out of the subpath's last vertex (BSDF or phase function) and sets
    // the densities: the next vertex's forward density (walk.pdf_dir) and the previous vertex's
    // reverse one. `scatter` gets the sample's weight (with the adjoint shading factor on light
    // subpaths). Returns false when sampling failed.
    bool scatter_from(Sampler& sampler, Walk& walk, VertexList& path, bool light,
                      Color& scatter) const {
        Vertex& v = path.back();
        Vertex& prev = path[path.size() - 2];
        const Vec3 wi = -walk.ray.d;
        Vec3 wo;
        double pdf_rev_dir = 0;
        if (v.kind == Vertex::Kind::Medium) {
            if (steady_angular_) {
                wo = v.phase->sample(wi, sampler.next_2d());
                walk.pdf_dir = v.phase->eval(wi, wo);
                scatter = Color(1.f);
            } else if (!angular_direction(sampler, walk, v, scatter, wo)) {
                return false;
            }
            pdf_rev_dir = v.phase->eval(wo, wi);  // (time-angular: angular_densities())
            walk.ray = Ray{v.p, wo, 0.f, kInfinity};
        } else {
            const float u_lobe = sampler.next_1d();
            const BsdfSample bs =
                light ? sample_adjoint(*v.bsdf, v.hit, v.hit.wi, u_lobe, sampler.next_2d())
                      : v.bsdf->sample(v.hit, v.hit.wi, u_lobe, sampler.next_2d());
            if (!bs.valid() || bs.weight.is_black()) return false;
            wo = v.hit.to_world(bs.wo);
            scatter = bs.weight;
            if (light) scatter *= adjoint_shading_factor(v.hit, wi, wo);
            if (bs.sampled_lobe & kBsdfDelta) {
                v.delta = true;
                walk.pdf_dir = 0;
            } else {
                walk.pdf_dir = bs.pdf;
                pdf_rev_dir = v.bsdf->pdf(v.hit, bs.wo, v.hit.wi);
            }
            walk.medium.refract(bs);
            walk.medium.cross(v.hit, wo);
            walk.ray = v.hit.spawn(wo);
        }
        prev.pdf_rev = v.delta ? 0 : back_of(v, prev).to_area(pdf_rev_dir) * v.segment_rev;
        return true;
    }

    // Time-angular sampling at medium vertex v (ch. 5.6.3), as transient_path does it: the next
    // distance first (kept in walk.next_u for next_vertex()), then a direction by the angular
    // strategy given that distance, mixed half-half with the phase function under `mis`.
    // `scatter` gets the phase function over the direction's density given the distance.
    bool angular_direction(Sampler& sampler, Walk& walk, const Vertex& v, Color& scatter,
                           Vec3& wo) const {
        const DistanceMixture& strategy = walk.segment.mixture(*v.medium.medium);
        walk.next_u = double(sampler.next_1d());
        const AngularQuery q{
            v.p, v.wi, v.phase, strategy.sample(walk.next_u), walk.has_target, walk.target};
        const AngularMixture::Sample as = AngularMixture(*angular_, mis_).sample(q, sampler);
        if (!(as.pdf > 0) || !std::isfinite(as.pdf)) return false;
        wo = as.wo;
        scatter = Color(float(as.phase / as.pdf));
        walk.pdf_dir = as.pdf;
        return true;
    }

    // ---- strategies --------------------------------------------------------------------------

    // s = 0: the camera subpath's last vertex is on an emitter (clock: before its delay).
    void emitter_hit(const Scene& scene, Sampler& sampler, const Subpaths& paths,
                     const Throughput& beta, const PathClock& clock,
                     const ContributionList& out) const {
        const int t = int(paths.camera.size());
        if (!wanted(0, t)) return;
        if (t == 2 && hide_emitters()) return;
        const Vertex& v = paths.camera.back();
        const Color Le = v.emitter->eval(v.hit, towards(v, paths.camera[size_t(t) - 2]));
        if (Le.is_black()) return;
        Join join;
        join.path_time = clock.time();
        const float w = unweighted() ? 1.f : mis_weight(scene, paths, 0, t, join, nullptr, nullptr);
        const Color value = beta(Le * w);
        clock.record(value, *v.emitter, sampler);
        images_.add(0, t, out.film_position(), value);
    }

    // s = 0 with an environment: the camera subpath left the scene in vacuum along walk.ray.
    // Each environment is the path's light vertex for a moment (a direction, at its plane
    // wave's start), for the MIS weight.
    void environment_hit(const Scene& scene, Sampler& sampler, const Walk& walk, Subpaths& paths,
                         const Throughput& beta, const PathClock& clock,
                         const ContributionList& out) const {
        const int t = int(paths.camera.size()) + 1;
        if (!wanted(0, t) || (t == 2 && hide_emitters())) return;
        const Vec3 d = walk.ray.d;
        const double eta = walk.medium.eta();
        for (const Emitter* env : scene.environment()) {
            Vertex& v = paths.camera.add();
            v.kind = Vertex::Kind::Light;
            v.environment = true;
            v.emitter = env;
            v.p = scene.sphere().plane_wave_start(clock.position(), d);
            v.n = -d;
            v.wi = -d;
            v.medium = walk.medium;
            set_forward_density(walk, paths.camera[paths.camera.size() - 2], v);
            Join join;
            join.path_time =
                clock.time() + scene.sphere().plane_wave_distance(clock.position(), d) * eta;
            const float w =
                unweighted() ? 1.f : mis_weight(scene, paths, 0, t, join, nullptr, nullptr);
            paths.camera.pop_back();
            const Color value = beta(env->eval_environment(d) * w);
            clock.record_distant(value, *env, sampler, d, eta);
            images_.add(0, t, out.film_position(), value);
        }
    }

    // Joins the first s light vertices and the first t camera vertices (s, t >= 1).
    void connect(const Scene& scene, Sampler& sampler, const Subpaths& paths, int s, int t,
                 ContributionList& out) const {
        if (t == 1) return to_sensor(scene, sampler, paths, s, out);
        if (s == 1) return light_sample(scene, sampler, paths, t, out);
        const Vertex& lv = paths.light[size_t(s) - 1];
        const Vertex& cv = paths.camera[size_t(t) - 1];
        if (!lv.connectible() || !cv.connectible()) return;
        const PathClock& clock = paths.camera_clock[size_t(t) - 1];
        const LightClock& light_clock = paths.light_clock[size_t(s) - 1];
        const double distance = distance_between(cv.p, lv.p);
        if (!(distance > 0) || !clock.arrives_in_time(light_clock, distance)) return;
        const Vec3 to_light = towards(cv, lv);
        const Color arriving = light_toward(paths, s, -to_light);
        const Color f_camera = scattering(cv, to_light, false);
        if (arriving.is_black() || f_camera.is_black()) return;
        SegmentDensities& segment = fresh_segment(paths);
        const ShadowConnection c =
            connection(scene, sampler, cv, lv.p, to_light, distance, segment);
        if (c.blocked()) return;
        const float g = float(1.0 / (distance * distance));
        const Join join{segment.forward(lv.kind == Vertex::Kind::Medium),
                        segment.backward(cv.kind == Vertex::Kind::Medium),
                        c.optical_length,
                        segment.single_medium(),
                        clock.time() + c.optical_length + light_clock.time() - paths.emission_time,
                        &to_light};
        const float w = unweighted() ? 1.f : mis_weight(scene, paths, s, t, join, nullptr, nullptr);
        const Color value =
            paths.camera_beta[size_t(t) - 1](f_camera * arriving * c.transmittance) * (g * w);
        clock.record(value, light_clock, c.optical_length);
        images_.add(s, t, out.film_position(), value);
    }

    // s = 1: a light sample for camera vertex t - 1 (next-event estimation).
    void light_sample(const Scene& scene, Sampler& sampler, const Subpaths& paths, int t,
                      const ContributionList& out) const {
        const Vertex& cv = paths.camera[size_t(t) - 1];
        if (!cv.connectible()) return;
        const EmitterSample ls = sample_emitter(scene, cv.p, sampler);
        if (!(ls.pdf > 0) || ls.weight.is_black()) return;
        const PathClock& clock = paths.camera_clock[size_t(t) - 1];
        if (std::isfinite(ls.distance) && double(ls.distance) > clock.remaining()) return;
        const Color f = scattering(cv, ls.wi, false);
        if (f.is_black()) return;
        SegmentDensities& segment = fresh_segment(paths);
        const ShadowConnection c =
            cv.kind == Vertex::Kind::Surface
                ? connect_to_light(scene, cv.hit, ls, cv.medium, sampler, &segment)
                : connect_to_light(scene, cv.p, ls, cv.medium, sampler, &segment);
        if (c.blocked()) return;
        Vertex& light = paths.connection_end;
        light.reuse();
        light.kind = Vertex::Kind::Light;
        light.p = ls.p;
        light.n = ls.n;
        light.emitter = ls.emitter;
        light.emission.p = ls.p;
        light.emission.n = ls.n;
        light.emission.delta_position = ls.emitter->is_delta();  // no camera path hits it
        light.emission.delta_direction = starts_.delta_direction(*ls.emitter);
        light.environment = ls.emitter->is_infinite() && !ls.emitter->is_delta();
        light.pdf_fwd = pdf_light_origin(scene, light);
        const Join join{segment.forward(false), segment.backward(cv.kind == Vertex::Kind::Medium),
                        c.optical_length, segment.single_medium(), clock.time() + c.optical_length};
        const float w = unweighted() ? 1.f : mis_weight(scene, paths, 1, t, join, &light, nullptr);
        const Color value = paths.camera_beta[size_t(t) - 1](f * ls.weight * c.transmittance) * w;
        clock.record(value, *ls.emitter, sampler, c.optical_length);
        images_.add(1, t, out.film_position(), value);
    }

    // t = 1: light vertex s - 1 seen by the camera, a splat.
    void to_sensor(const Scene& scene, Sampler& sampler, const Subpaths& paths, int s,
                   ContributionList& out) const {
        if (s == 1 && hide_emitters()) return;
        const Vertex& lv = paths.light[size_t(s) - 1];
        if (!lv.connectible() || !out.splat_list()) return;
        const SensorSample ss = scene.sensor().sample_direct(lv.p, sampler.next_2d());
        const LightClock& clock = paths.light_clock[size_t(s) - 1];
        if (!ss.valid() || !clock.arrives_in_time(ss.distance)) return;
        const Color value = light_toward(paths, s, ss.wi);
        if (value.is_black()) return;
        SegmentDensities& segment = fresh_segment(paths);
        const ShadowConnection c =
            lv.kind == Vertex::Kind::Surface
                ? connect_to_sensor(scene, lv.hit, ss, lv.medium, sampler, &segment)
                : connect_to_sensor(scene, lv.p, ss,
                                    lv.kind == Vertex::Kind::Light
                                        ? starts_.medium(*lv.emitter, lv.emission, ss.wi)
                                        : lv.medium,
                                    sampler, lv.n, lv.emission.p_error, &segment);
        if (c.blocked()) return;
        Vertex& camera = paths.connection_end;
        camera.reuse();
        camera.kind = Vertex::Kind::Camera;
        camera.p = ss.p;
        camera.pdf_fwd = 1.f;
        const Join join{segment.backward(lv.kind == Vertex::Kind::Medium), segment.forward(false),
                        c.optical_length, segment.single_medium(),
                        clock.time() - paths.emission_time + c.optical_length};
        const float w = unweighted() ? 1.f : mis_weight(scene, paths, s, 1, join, nullptr, &camera);
        const Color splat = value * c.transmittance * (ss.weight * w);
        clock.record(*out.splat_list(), ss.pos, splat, c.optical_length);
        images_.add(s, 1, ss.pos, splat);
    }

    // Connection strategies (ch. 5.6.2, Fig. 5.6 middle): on the first piece of each ray the
    // camera subpath left along through a medium, a vertex placed by the <connection> strategy
    // aiming at each light vertex and joined to it. The placed vertex takes the place of the
    // distance-sampled last camera vertex of strategy (s, t); MIS weighs both variants.
    void place_and_connect(const Scene& scene, Sampler& sampler, const Subpaths& paths,
                           const DimensionLayout& dims, ContributionList& out) const {
        const int nl = int(paths.light.size());
        for (size_t j = 0; j < paths.camera_out.size(); ++j) {
            if (!paths.camera_out[j].medium.medium) continue;
            const int t = int(j) + 2;  // the camera vertices up to camera[j], and the placed one
            for (int s = 1; s <= nl; ++s) {
                if (max_depth() >= 0 && s + t - 1 > max_depth()) break;
                if (!wanted(s, t, true)) continue;
                sampler.advance_to(dims.placement(j, s));
                connect_placed(scene, sampler, paths, j, s, out);
            }
        }
    }

    // Places a vertex on camera_out[j] aiming at light vertex s - 1 and joins them.
    void connect_placed(const Scene& scene, Sampler& sampler, const Subpaths& paths, size_t j,
                        int s, ContributionList& out) const {
        const Subpaths::Outgoing& ray = paths.camera_out[j];
        const Vertex& lv = paths.light[size_t(s) - 1];
        const LightClock& light_clock = paths.light_clock[size_t(s) - 1];
        const PathClock& from = paths.camera_clock[j];
        const Medium& medium = *ray.medium.medium;
        const ConnectionQuery q =
            placement_query(scene, ray.ray.o, ray.ray.d, lv.p, medium.eta(),
                            from.time() + light_clock.time() - paths.emission_time);
        const double u = double(sampler.next_1d());
        if (!lv.connectible() || !(q.length > 0)) return;
        const double r = connection_->sample(q, u);
        const double pc = r >= 0 && r < ray.first_end ? connection_->pdf(q, r) : 0.0;
        if (!(pc > 0)) return;
        Vertex x;
        x.kind = Vertex::Kind::Medium;
        x.p = ray.ray.at(float(r));
        // A vertex on top of the ray's origin (a distance that rounds to 0) has no direction
        // from it, as in the walks: no contribution (probability zero in exact arithmetic).
        if (!(squared_length(x.p - ray.ray.o) > 0.f)) return;
        x.wi = -ray.ray.d;
        x.phase = &medium.phase();
        x.medium = ray.medium;
        PathClock clock = from;
        clock.travel_to(x.p, medium.eta());
        const double distance = distance_between(x.p, lv.p);
        if (!(distance > 0) || !clock.arrives_in_time(light_clock, distance)) return;
        // Its densities as the distance strategy would have placed it (for MIS).
        const DistanceMixture strategy(medium, distance_.get(), mis_, DistanceContext{window_end_});
        x.segment_fwd = strategy.pdf(r);
        x.segment_rev =
            paths.camera[j].kind == Vertex::Kind::Medium ? strategy.pdf(r) : strategy.survival(r);
        x.segment_optical = clock.time() - from.time();
        x.segment_single_medium = true;
        x.pdf_fwd = to_area(ray.pdf_dir, paths.camera[j], x) * x.segment_fwd;
        const Vec3 to_light = towards(x, lv);
        const Color f_camera = scattering(x, to_light, false);
        const Color arriving = light_toward(paths, s, -to_light);
        if (f_camera.is_black() || arriving.is_black()) return;
        SegmentDensities& segment = fresh_segment(paths);
        const ShadowConnection c = connection(scene, sampler, x, lv.p, to_light, distance, segment);
        if (c.blocked()) return;
        // The placed vertex's weight: transmittance and scattering over the placement density.
        const Color placed =
            medium.transmittance(ray.ray, r, sampler) * medium.sigma_s(x.p) * float(1.0 / pc);
        const Join join{segment.forward(lv.kind == Vertex::Kind::Medium), segment.backward(true),
                        c.optical_length, segment.single_medium(),
                        clock.time() + c.optical_length + light_clock.time() - paths.emission_time};
        const float w =
            unweighted() ? 1.f : mis_weight(scene, paths, s, int(j) + 2, join, nullptr, &x, true);
        const float g = float(1.0 / (distance * distance));
        const Color value = ray.beta(placed * f_camera * arriving * c.transmittance) * (g * w);
        clock.record(value, light_clock, c.optical_length);
        images_.add(s, int(j) + 2, out.film_position(), value);
    }

    // The light leaving light vertex s - 1 toward world direction d: what its emitter sends (s =
    // 1, over the density of the vertex) or what its BSDF or phase function scatters of the light
    // that arrived there, after its event's colour transfer.
    static Color light_toward(const Subpaths& paths, int s, const Vec3& d) {
        const Vertex& lv = paths.light[size_t(s) - 1];
        if (s == 1) return lv.emitter->eval_direction(lv.emission, d) / float(lv.pdf_fwd);
        return leaving(lv.event, scattering(lv, d, true) * paths.light_power[size_t(s) - 1]);
    }

    // What vertex v sends toward world direction d of what arrived from its previous vertex:
    // the BSDF value with its cosine (and, on light subpaths, the adjoint shading factor) or
    // the phase function. Zero for camera and light vertices (their terms are the strategies').
    static Color scattering(const Vertex& v, const Vec3& d, bool light) {
        if (v.kind == Vertex::Kind::Medium) return Color(v.phase->eval(v.wi, d));
        if (v.kind != Vertex::Kind::Surface) return Color(0.f);
        if (!light) return v.bsdf->eval(v.hit, v.hit.wi, v.hit.to_local(d));
        return eval_adjoint(*v.bsdf, v.hit, v.hit.wi, v.hit.to_local(d)) *
               adjoint_shading_factor(v.hit, v.wi, d);
    }

    // The shadow connection from camera vertex cv toward point `to`; `segment` hears of its
    // media.
    static ShadowConnection connection(const Scene& scene, Sampler& sampler, const Vertex& cv,
                                       const Vec3& to, const Vec3& dir, double distance,
                                       SegmentDensities& segment) {
        EmitterSample target;  // connect_to_light() needs only the point, direction, distance
        target.p = to;
        target.wi = dir;
        target.distance = float(distance);
        return cv.kind == Vertex::Kind::Surface
                   ? connect_to_light(scene, cv.hit, target, cv.medium, sampler, &segment)
                   : connect_to_light(scene, cv.p, target, cv.medium, sampler, &segment);
    }

    // ---- multiple importance sampling --------------------------------------------------------

    // Density with which vertex v, arrived at from direction w_prev (unit, toward where the
    // path came from; unused for end points), samples `next`, as a density of next.
    double pdf(const Scene& scene, const Vertex& v, const Vec3& w_prev, const Vertex& next) const {
        return pdf(scene, v, w_prev, next, towards(v, next));
    }
    // The same with d = towards(v, next) already known (mis_weight(): the connection's
    // direction, found once for the four densities across it).
    double pdf(const Scene& scene, const Vertex& v, const Vec3& w_prev, const Vertex& next,
               const Vec3& d) const {
        switch (v.kind) {
            case Vertex::Kind::Camera:
                return to_area(scene.sensor().pdf_direction(d), v, next);
            case Vertex::Kind::Light:
                return pdf_light(v, next, d);
            case Vertex::Kind::Medium:
                return to_area(v.phase->eval(w_prev, d), v, next);
            case Vertex::Kind::Surface:
                return to_area(v.bsdf->pdf(v.hit, v.hit.to_local(w_prev), v.hit.to_local(d)), v,
                               next);
        }
        return 0;
    }
    // The same toward `prev`, the vertex before v on its subpath, from the segment v keeps.
    double pdf_back(const Scene& scene, const Vertex& v, const Vec3& w_prev,
                    const Vertex& prev) const {
        const Vertex::Back& back = back_of(v, prev);
        switch (v.kind) {
            case Vertex::Kind::Medium:
                return back.to_area(v.phase->eval(w_prev, back.dir));
            case Vertex::Kind::Surface:
                return back.to_area(
                    v.bsdf->pdf(v.hit, v.hit.to_local(w_prev), v.hit.to_local(back.dir)));
            default:
                return pdf(scene, v, w_prev, prev, back.dir);
        }
    }
    // Density with which an emitter at v sends light toward `next` (v on an emitter: a light
    // vertex, or a camera vertex that hit one).
    // A light of a single direction (collimated) has no density of it: the next vertex takes
    // the light point's area density instead (the beam's cross-section dA_perp = |cos| dA at
    // a surface; in a medium dV = dA_perp dr), so the light vertex keeps only the emitter's
    // probability (pdf_light_origin()) and the path's density is unchanged.
    static double pdf_light(const Vertex& v, const Vertex& next) {
        return pdf_light(v, next, towards(v, next));
    }
    static double pdf_light(const Vertex& v, const Vertex& next, const Vec3& d) {  // d: to next
        EmissionSample at = v.emission;
        at.p = v.p;
        at.n = v.n;
        float pos = 0.f, dir = 0.f;
        v.emitter->pdf_emission(at, d, pos, dir);
        if (!v.emission.delta_direction && !v.environment) return to_area(dir, v, next);
        if (!next.on_surface()) return pos;
        return pos * std::abs(dot(next.n, d));
    }
    // Density with which a light subpath starts at v (on an emitter).
    static double pdf_light_origin(const Scene& scene, const Vertex& v) {
        const double pmf = scene.select_emitter_pmf(*v.emitter);
        if (v.emission.delta_direction) return pmf;  // the next vertex has the position's
        if (v.environment) return pmf * v.emitter->pdf_environment(-v.n);  // and here too
        EmissionSample at;
        at.p = v.p;
        at.n = v.n;
        float pos = 0.f, dir = 0.f;
        v.emitter->pdf_emission(at, v.n, pos, dir);
        return pos * pmf;
    }

    // A path made by strategy (s, t), in light-to-camera order: x_0 .. x_{s-1} the light
    // vertices, x_s .. x_{n-1} the camera vertices reversed. `light` / `camera` replace the end
    // vertex a strategy sampled itself (s = 1: the light sample; t = 1: the sensor point; a
    // vertex placed by the connection strategy).
    struct PathView {
        const Subpaths& paths;
        int s, t;
        const Vertex* light;
        const Vertex* camera;
        const Join& join;

        int size() const { return s + t; }
        const Vertex& light_vertex(int i) const {
            return (i == s - 1 && light) ? *light : paths.light[size_t(i)];
        }
        const Vertex& camera_vertex(int j) const {  // camera vertex j is x_{n-1-j}
            return (j == t - 1 && camera) ? *camera : paths.camera[size_t(j)];
        }
        const Vertex& operator[](int i) const {
            return i < s ? light_vertex(i) : camera_vertex(s + t - 1 - i);
        }
        // Whether x_i was scattered by a delta lobe. The connection's end points were not.
        bool delta(int i) const { return i != s && i != s - 1 && (*this)[i].delta; }
        // Whether strategy k (joining x_{k-1} and x_k) could have made this path: neither end
        // scattered by a delta lobe, nor (k = 0) a light emitting a delta (`delta_light`). An
        // environment's light vertex lies on no surface the camera could connect to (k = 1).
        bool joinable(int k, bool delta_light) const {
            if (k == 1 && s + t == 2 && (*this)[0].environment) return false;
            if (k == s) return true;
            if (k > s) return !delta(k - 1) && !delta(k);
            return !delta(k) && !(k > 0 ? delta(k - 1) : delta_light);
        }
        // The segment between x_i and x_{i+1}: its optical length, whether it lies in one
        // medium, and the distance densities of reaching x_i walking from x_{i+1} and of
        // reaching x_{i+1} walking from x_i.
        struct Segment {
            double optical;
            bool single_medium;
            double toward_light, toward_camera;
        };
        Segment segment(int i) const {
            if (i + 1 < s) {
                const Vertex& b = light_vertex(i + 1);
                return {b.segment_optical, b.segment_single_medium, b.segment_rev, b.segment_fwd};
            }
            if (i + 1 == s)
                return {join.optical, join.single_medium, join.at_light_end, join.at_camera_end};
            const Vertex& a = (*this)[i];
            return {a.segment_optical, a.segment_single_medium, a.segment_fwd, a.segment_rev};
        }
    };

    // The weight of strategy (s, t) for the path it made: the heuristic over every strategy
    // (s', t') with s' + t' = s + t that could have sampled it (Veach 1997, ch. 10; pbrt-v3's
    // MISWeight), and over the connection strategy's variant of each (placement_factor()).
    // `join` describes the strategy's own connection (PathView for `light` and `camera`);
    // `placed`: the strategy is the connection strategy's variant of (s, t). A medium vertex's
    // densities include those of the distance strategy that placed it, so the weights favour
    // the strategies whose distances fit the path (the time-sampling strategies of ch. 5.6).
    float mis_weight(const Scene& scene, const Subpaths& paths, int s, int t, const Join& join,
                     const Vertex* light, const Vertex* camera, bool placed = false) const {
        const PathView path{paths, s, t, light, camera, join};
        // The connection changes the densities of its end points and their neighbours only, so
        // with steady directions and no placed vertices the strategies near it are summed from
        // those and the rest from the subpaths' own sums. Time-angular directions and placed
        // vertices make densities depend on the whole path: all strategies are summed then.
        if (steady_angular_ && !connecting_) return local_weight(scene, path);
        return whole_path_weight(scene, path, placed);
    }
    // What a connection changes: the densities of its end points and their neighbours sampled
    // from its other side. x_s (the camera end) and x_{s+1} from the light side; x_{s-1} (the
    // light end) and x_{s-2} from the camera side (0 where a vertex does not exist).
    struct Across {
        double end_from_light = 0, beyond_end_from_light = 0;    // x_s, x_{s+1}
        double end_from_camera = 0, beyond_end_from_camera = 0;  // x_{s-1}, x_{s-2}
    };
    Across across_densities(const Scene& scene, const PathView& path) const {
        const int s = path.s, t = path.t;
        const Vertex& pt = path.camera_vertex(t - 1);
        Across a;
        if (s == 0) {  // pt is on an emitter: the light side is its emission
            a.end_from_light = pdf_light_origin(scene, pt);
            a.beyond_end_from_light = pdf_light(pt, path.camera_vertex(t - 2)) * pt.segment_rev;
            return a;
        }
        const Vertex& qs = path.light_vertex(s - 1);
        // towards(pt, qs), and -d = towards(qs, pt), exactly
        const Vec3 d = path.join.across ? *path.join.across : towards(pt, qs);
        a.end_from_light = pdf(scene, qs, qs.wi, pt, -d) * path.join.at_camera_end;
        if (t > 1)
            a.beyond_end_from_light =
                pdf_back(scene, pt, d, path.camera_vertex(t - 2)) * pt.segment_rev;
        a.end_from_camera = pdf(scene, pt, pt.wi, qs, d) * path.join.at_light_end;
        if (s > 1)
            a.beyond_end_from_camera =
                pdf_back(scene, qs, -d, path.light_vertex(s - 2)) * qs.segment_rev;
        return a;
    }
    // mis_weight() with steady directions and no placed variants: strategies s - 2 .. s + 2
    // from the densities the connection changes (Across) and the vertices' own, those beyond
    // from far_sums(). The terms of whole_path_weight(), in its order, without its arrays.
    float local_weight(const Scene& scene, const PathView& path) const {
        const int s = path.s, t = path.t, n = s + t;
        const int last = to_sensor_ ? n - 1 : n - 2;  // the last strategy: t = 1 or t = 2
        const int lo = std::max(0, s - 2), hi = std::min(last, s + 2);
        const Across a = across_densities(scene, path);
        // Strategy k's density relative to strategy s's: rel[k - s + 2].
        double rel[5] = {0, 0, 1.0, 0, 0};
        if (hi >= s + 1) rel[3] = ratio(a.end_from_light, path.camera_vertex(t - 1).pdf_fwd);
        if (hi >= s + 2)
            rel[4] = rel[3] * ratio(a.beyond_end_from_light, path.camera_vertex(t - 2).pdf_fwd);
        if (lo <= s - 1) rel[1] = ratio(a.end_from_camera, path.light_vertex(s - 1).pdf_fwd);
        if (lo <= s - 2)
            rel[0] = rel[1] * ratio(a.beyond_end_from_camera, path.light_vertex(s - 2).pdf_fwd);
        const bool delta_light = s > 0 && delta_emission(path.light_vertex(0));
        double sum = 0.0;
        for (int k = lo; k <= hi; ++k)
            if (path.joinable(k, delta_light)) sum += h(rel[k - s + 2]);
        if (lo > 0) sum += h(rel[lo - s + 2]) * far_sums(path.paths, true, lo - 1);
        if (hi < last) sum += h(rel[hi - s + 2]) * far_sums(path.paths, false, n - 1 - hi);
        return float(1.0 / sum);
    }
    // mis_weight() over every strategy of the path: each vertex's density from either side,
    // and `rel`, the density of strategy k (joining x_{k-1} and x_k) relative to strategy s.
    struct Densities {
        double from_light, from_camera, rel;
    };
    float whole_path_weight(const Scene& scene, const PathView& path, bool placed) const {
        const int s = path.s, n = path.size();
        // Time-angular: an emitter hit right after a medium vertex is left to the other
        // strategies (as transient_path leaves it to light sampling). Its direction aimed at
        // another light point, and its density at the point hit (the target's own, infinite
        // when aimed at it) would not describe it.
        const bool hit_excluded = !steady_angular_ && path[1].kind == Vertex::Kind::Medium;
        if (s == 0 && hit_excluded) return 0.f;
        const int last = to_sensor_ ? n - 1 : n - 2;  // the last strategy: t = 1 or t = 2
        // On the stack for the usual depths (a thread_local vector costs a TLS lookup per call).
        constexpr int kStack = 64;
        Densities stack[kStack];
        std::vector<Densities> heap(n > kStack ? size_t(n) : 0);
        Densities* x = n > kStack ? heap.data() : stack;
        for (int i = 0; i < s; ++i) {
            const Vertex& v = path.light_vertex(i);
            x[size_t(i)] = {v.pdf_fwd, v.pdf_rev, 0};
        }
        for (int i = s; i < n; ++i) {
            const Vertex& v = path.camera_vertex(n - 1 - i);
            x[size_t(i)] = {v.pdf_rev, v.pdf_fwd, 0};
        }
        const Across a = across_densities(scene, path);
        x[size_t(s)].from_light = a.end_from_light;
        if (s + 1 < n) x[size_t(s) + 1].from_light = a.beyond_end_from_light;
        if (s > 0) x[size_t(s) - 1].from_camera = a.end_from_camera;
        if (s > 1) x[size_t(s) - 2].from_camera = a.beyond_end_from_camera;
        if (!steady_angular_) angular_densities(path, x);
        x[size_t(s)].rel = 1.0;
        for (int k = s + 1; k <= last; ++k)  // strategies with fewer camera vertices
            x[size_t(k)].rel = x[size_t(k) - 1].rel *
                               ratio(x[size_t(k) - 1].from_light, x[size_t(k) - 1].from_camera);
        for (int k = s - 1; k >= 0; --k)  // strategies with fewer light vertices
            x[size_t(k)].rel =
                x[size_t(k) + 1].rel * ratio(x[size_t(k)].from_camera, x[size_t(k)].from_light);
        // (s = 0 runs while the camera subpath is traced: the light subpath is not there yet.)
        const bool delta_light = s > 0 && delta_emission(path.light_vertex(0));
        double sum = 0.0;
        double placed_factor = 0.0;  // strategy s's (k = s always joins)
        for (int k = 0; k <= last; ++k) {
            if (!path.joinable(k, delta_light) || (k == 0 && hit_excluded)) continue;
            sum += h(x[size_t(k)].rel);
            if (!connecting_) continue;  // no placed variants (placement_factor() would be 0)
            if (const double c = placement_factor(scene, path, k); c > 0) {
                sum += h(x[size_t(k)].rel * c);
                if (k == s) placed_factor = c;
            }
        }
        return float((placed ? h(placed_factor) : 1.0) / sum);
    }
    // A light subpath's start emitting a delta in position or direction: no camera path hits
    // it, so the strategy joining the camera subpath to it (k = 0) cannot make the path.
    static bool delta_emission(const Vertex& start) {
        return start.emission.delta_position || start.emission.delta_direction;
    }
    // The heuristic's function of a density ratio (multiplicative: h(ab) = h(a) h(b)).
    double h(double r) const { return power_ ? r * r : r; }
    // A ratio of densities; a zero density (a delta lobe's) stands for 1, as in pbrt-v3.
    static double ratio(double num, double den) {
        return (num != 0 ? num : 1.0) / (den != 0 ? den : 1.0);
    }
    // Strategies far from a connection, for mis_weight(). At light vertex m: the sum, over the
    // strategies k <= m (joining light vertices k - 1 and k) that can join, of h(the product
    // over i = k..m of vertex i's density from the camera side over its own); at camera vertex
    // m the same over the strategies keeping camera vertices 0..t' - 1, 1 (or 2) <= t' <= m.
    // These densities are the subpath's own (a connection (s, t) changes those of path
    // vertices s - 2 .. s + 1 only) and h is multiplicative, so mis_weight() needs only
    // h(its strategy s - 2's or s + 2's relative density) times this: O(1) per connection
    // instead of O(path length) (the recursive MIS of van Antwerpen 2011 and Georgiev 2012).
    // Filled on demand: a vertex's reverse density is known once the vertex after it has
    // scattered, which holds for every vertex a connection asks for here.
    // (A sum found before is read inline; only filling new ones is a call.)
    double far_sums(const Subpaths& paths, bool light, int m) const {
        const std::vector<double>& sums = light ? paths.light_far : paths.camera_far;
        return size_t(m) < sums.size() ? sums[size_t(m)] : fill_far_sums(paths, light, m);
    }
    [[gnu::noinline]] double fill_far_sums(const Subpaths& paths, bool light, int m) const {
        std::vector<double>& sums = light ? paths.light_far : paths.camera_far;
        const VertexList& path = light ? paths.light : paths.camera;
        const int first_joinable = light ? 0 : (to_sensor_ ? 1 : 2);  // camera: t' >= 1 or 2
        for (int i = int(sums.size()); i <= m; ++i) {
            const Vertex& v = path[size_t(i)];
            const double before = i > 0 ? sums[size_t(i) - 1] : 0.0;
            if (i < first_joinable) {
                sums.push_back(0.0);
                continue;
            }
            const bool previous_delta = i > 0 ? path[size_t(i) - 1].delta : delta_emission(v);
            const double joins = !v.delta && !previous_delta ? 1.0 : 0.0;
            sums.push_back(h(ratio(v.pdf_rev, v.pdf_fwd)) * (joins + before));
        }
        return sums[size_t(m)];
    }

    // Time-angular sampling: the densities of leaving each medium vertex of the path toward its
    // neighbours, which the subpaths' own depend on (the distance drawn before the direction,
    // and the point aimed at). Each is the density at the distance to that neighbour, aiming at
    // the path's camera end (toward the camera) or its light end (toward the light): the joint
    // density of direction and distance where the neighbour is a medium vertex on the
    // segment's first piece, and elsewhere a function of the path alone, so every strategy of a
    // path computes the same weights.
    void angular_densities(const PathView& path, Densities* x) const {
        const int n = path.size();
        const Vec3 camera_end = path[n - 1].p, light_end = path[0].p;
        for (int i = 1; i + 1 < n; ++i) {
            const Vertex& v = path[i];
            if (v.kind != Vertex::Kind::Medium) continue;
            const Vertex &toward_light = path[i - 1], &toward_camera = path[i + 1];
            x[size_t(i) + 1].from_light =
                angular_pdf(v, towards(v, toward_light), toward_camera, camera_end) *
                path.segment(i).toward_camera;
            x[size_t(i) - 1].from_camera =
                angular_pdf(v, towards(v, toward_camera), toward_light, light_end) *
                path.segment(i - 1).toward_light;
        }
    }
    // The density (area or volume measure) of time-angular sampling at medium vertex v, arrived
    // at from w_prev and aiming at `target`, choosing `next` at the distance to it.
    double angular_pdf(const Vertex& v, const Vec3& w_prev, const Vertex& next,
                       const Vec3& target) const {
        const Vec3 d = towards(v, next);
        const AngularQuery q{v.p, w_prev, v.phase, distance_between(v.p, next.p), true, target};
        return to_area(AngularMixture(*angular_, mis_).pdf(q, double(v.phase->eval(w_prev, d)), d),
                       v, next);
    }

    // The connection strategy's variant of strategy k: its last camera vertex x_k placed on the
    // ray from x_{k+1} by the <connection> strategy aiming at x_{k-1}, instead of by distance
    // sampling. Returns the density of that placement relative to the distance-sampled one, or
    // 0 where it cannot make the path: x_k not in a medium, or a boundary between x_{k+1} and
    // x_k (a vertex is placed on the first piece of a ray only), or x_{k-1} not connectible.
    double placement_factor(const Scene& scene, const PathView& path, int k) const {
        if (!connecting_ || k < 1 || k > path.size() - 2) return 0;
        const Vertex& placed = path[k];
        if (placed.kind != Vertex::Kind::Medium) return 0;
        const PathView::Segment in = path.segment(k);
        if (!in.single_medium || !(in.toward_light > 0)) return 0;
        const Vertex& target = path[k - 1];
        if (!target.connectible()) return 0;
        const Vertex& from = path[k + 1];
        const double elapsed = path.join.path_time - in.optical - path.segment(k - 1).optical;
        const ConnectionQuery q = placement_query(scene, from.p, towards(from, placed), target.p,
                                                  placed.medium.eta(), elapsed);
        return connection_->pdf(q, distance_between(from.p, placed.p)) / in.toward_light;
    }

    // The segment of a ray from `origin` along `d` (in a medium of index eta) on which a vertex
    // can still connect to `target` within the window when the rest of the path takes
    // `elapsed` (optical length and delays, without the emission time): the connection
    // strategy's query. In world time no such bound is known before the path is complete, and
    // the strategy places vertices on the whole ray (line_to_point is then equiangular).
    static ConnectionQuery placement_query(const Scene& scene, const Vec3& origin, const Vec3& d,
                                           const Vec3& target, double eta, double elapsed) {
        const double cut = scene.time_window().path_cut();  // infinite in world time
        return {origin, d, connection_reach(origin, d, target, eta, cut - elapsed), target};
    }

    // strategy_images: the weighted contributions of each strategy (s, t), summed per pixel
    // (box filter, no time), written as OUTBASE_bdpt_s<s>_t<t>.exr. Threads add concurrently,
    // so these debugging images are not bit-identical across thread counts (the film is).
    struct StrategyImages {
        bool enabled = false;
        int width = 0, height = 0, depth = 0;
        float camera_weight = 1;                        // Sensor::ray_weight()
        mutable std::vector<std::atomic<double>> sums;  // [(s * (depth + 2) + t) * pixels][3]
        void prepare(int w, int h, int d, float ray_weight) {
            width = w, height = h, depth = d, camera_weight = ray_weight;
            sums = std::vector<std::atomic<double>>(size_t(d + 1) * size_t(d + 2) * size_t(w) *
                                                    size_t(h) * 3);
        }
        size_t offset(int s, int t) const {
            return size_t(s * (depth + 2) + t) * size_t(width) * size_t(height) * 3;
        }
        // Every contribution passes here: the test is inlined, the rest is not (a call per
        // contribution cost ~0.4 % of a render without the images).
        void add(int s, int t, Vec2 pos, const Color& value) const {
            if (enabled) add_enabled(s, t, pos, value);
        }
        [[gnu::noinline]] void add_enabled(int s, int t, Vec2 pos, Color value) const {
            if (!value.is_finite()) return;
            if (t >= 2) value *= camera_weight;  // what the renderer applies to camera samples
            const int x = std::clamp(int(pos.x), 0, width - 1),
                      y = std::clamp(int(pos.y), 0, height - 1);
            const size_t i = offset(s, t) + (size_t(y) * size_t(width) + size_t(x)) * 3;
            for (int c = 0; c < 3; ++c) sums[i + size_t(c)].fetch_add(double(value[c]));
        }
    };

    StrategyImages images_;
    SourceLocation images_location_;
    bool power_ = true;
    bool light_image_ = true;  // strategies t = 1 wanted (Mitsuba's lightImage)
    bool to_sensor_ = true;    // ... and the sensor can be connected to
    std::shared_ptr<DistanceSampler> distance_;
    std::shared_ptr<ConnectionSampler> connection_;
    std::shared_ptr<AngularSampler> angular_;
    bool steady_angular_ = true;     // directions at medium vertices from the phase function
    bool connecting_ = false;        // the connection strategy places vertices
    bool only_placed_ = false;       // debugging: strategy_s/t's connection-strategy variant
    bool mis_ = false;               // distances: a mixture of the strategy and mean free paths
    double window_end_ = kInfinity;  // the film's window end (exponential distances' rate)
    int only_s_ = -1, only_t_ = -1;  // debugging: one strategy alone, unweighted
    int only_length_ = -1;           // debugging: paths of this many segments only
    LightPathStarts starts_;
};

// The two plugins built from this file (CMakeLists.txt): they differ only in their defaults.
#ifdef FEMTO_MITSUBA_BDPT
class MitsubaBdpt final : public Bdpt {
public:
    explicit MitsubaBdpt(const Properties& props) : Bdpt(props, 5) {}
};
#else
class TransientBdpt final : public Bdpt {
public:
    explicit TransientBdpt(const Properties& props) : Bdpt(props, 0) {}
};
#endif

}  // namespace

#define FEMTO_BDPT_PARAMS                                                                          \
    {"heuristic", "string", "power", "MIS heuristic: power or balance"},                           \
        {"light_image", "boolean", "true",                                                         \
         "use the strategies t = 1 (light subpath vertices connected to the sensor and splatted; " \
         "Mitsuba's lightImage)"},                                                                 \
        {"sample_direct", "boolean", "true",                                                       \
         "accepted for Mitsuba 0.6 scenes; femto always samples emitters and the sensor "          \
         "directly (false is ignored with a note)"},                                               \
        {"strategy_s", "integer", "-1",                                                            \
         "debugging: render only strategy (strategy_s, strategy_t), unweighted"},                  \
        {"strategy_t", "integer", "-1", "debugging: see strategy_s"},                              \
        {"strategy_images", "boolean", "false",                                                    \
         "also write OUTBASE_bdpt_s<s>_t<t>.exr: each strategy's weighted contributions "          \
         "(steady, box-filtered; needs a finite max_depth)"},                                      \
        {"path_length", "integer", "-1",                                                           \
         "debugging: render only paths of this many segments (all their strategies, weighted)"},   \
        {"distance", "distance", "mean_free_path",                                                 \
         "distance sampling in media on both subpaths (nested <distance>): mean_free_path or "     \
         "exponential"},                                                                           \
        {"mis", "boolean", "false",                                                                \
         "combine the distance strategy with mean-free-path sampling (one-sample MIS)"},           \
        {"connection", "connection", "deterministic",                                              \
         "connection strategy (nested <connection>): deterministic adds nothing; line_to_point "   \
         "or equiangular also place a vertex on each camera ray through a medium toward each "     \
         "light vertex, weighed by MIS against the other strategies"},                             \
        {"strategy_placed", "boolean", "false",                                                    \
         "debugging, with strategy_s/strategy_t: render the connection strategy's variant of "     \
         "that strategy alone"},                                                                   \
    {                                                                                              \
        "angular", "angular", "phase",                                                             \
            "directions at medium vertices on both subpaths (nested <angular>): phase or time "    \
            "(light subpaths aim at the camera, camera subpaths at the light subpath's start)"     \
    }

#ifdef FEMTO_MITSUBA_BDPT
FEMTO_PLUGIN(MitsubaBdpt, femto::PluginKind::Integrator, "bdpt",
             "Mitsuba 0.6's bidirectional path tracer: transient_bdpt with Russian roulette from "
             "depth 5",
             {FEMTO_BDPT_PARAMS})
#else
FEMTO_PLUGIN(TransientBdpt, femto::PluginKind::Integrator, "transient_bdpt",
             "Transient bidirectional path tracer: every (s, t) strategy with MIS, surfaces and "
             "media, each contribution at its own time",
             {{"rr_depth", "integer", "0",
               "subpath depth at which Russian roulette starts; 0 = never (max_depth or the window "
               "end paths)"},
              FEMTO_BDPT_PARAMS})
#endif
