// transient_ppm: transient progressive photon mapping on surfaces and in media (thesis ch.
// 5.5.1 and appendix 5.B; Knaus & Zwicker's probabilistic PPM, which the appendix follows;
// Jensen & Christensen's volumetric photons for media).
//
// Every pass (one iteration j = 1, 2, ...) does two things:
//   - begin_pass() traces `photons_per_pass` photon paths from the emitters, as the light
//     tracer's paths (pulses, delays, eta, adjoint shading factors, mean-free-path sampling in
//     media), and stores a photon at every surface vertex with a non-delta lobe and at every
//     medium vertex: its position, incoming direction, power and time (its LightClock's:
//     emission time + optical length + delays), in two maps (surfaces, media);
//   - sample() follows each camera ray through delta bounces (mirrors, glass) and, in media,
//     samples a distance by the mean free path; at its first vertex with a non-delta lobe it
//     estimates the light leaving toward the camera from the surface photons within R_j
//     (eq. 5.54): each photon i adds
//         throughput * f(wo, wi_i) * power_i * K_R(|x - x_i|)
//     at time t_eye + t_i spread by the temporal kernel K_T of half-width T_j, which the film
//     integrates exactly over its bins (Contribution::kernel). At a medium vertex the same sum
//     runs over the volume photons with the phase function for f and a 3D kernel, divided by
//     sigma_s there (the photons' density is sigma_s times the radiance). Emitters seen through
//     delta bounces are added as the path tracer adds them.
// The pixel estimate is the average over passes (eq. 5.55). Both bandwidths shrink with the
// pass (eq. 5.58, femto::ProgressiveBandwidths): T_j = T_1 s_j^beta_T and
// R_j^d = R_1^d s_j^(1 - beta_T), s_j = progressive_shrink(alpha, j - 1); on surfaces (d = 2)
// alpha = 4/7 and beta_T = 1/3 minimise the AMSE (5.B.4), in media (d = 3) alpha = 1/2 and
// beta_T = 1/4 (docs/photon-mapping.md derives them).
//
// Film rule: the estimate smooths time with its own kernel, so a time-resolved film must use
// `<tfilter type="histogram"/>` (no second smoothing); steady films ignore time (ordinary PPM).
// Depth: a photon that reached its vertex after d_l segments joins an eye path of d_e segments
// only when d_e + d_l <= max_depth, so max_depth means what it means for transient_path.
// docs/photon-mapping.md derives the defaults of R_1 and T_1.

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "femto/density_estimation.h"
#include "femto/integrator.h"
#include "femto/kernel.h"
#include "femto/medium.h"
#include "femto/path_clock.h"
#include "femto/photon_tracing.h"
#include "femto/plugin.h"
#include "femto/point_grid.h"
#include "femto/random.h"
#include "femto/sensor.h"
#include "femto/tfilter.h"
#include "femto/transport.h"

namespace {

using namespace femto;

// What a photon leaves at a surface or medium vertex.
struct Photon {
    Vec3 wi;        // toward where it came from (world)
    Color power;    // flux it carries (emitted / densities / photons per pass)
    double time;    // its LightClock's time at the vertex
    int32_t depth;  // segments from the emitter to the vertex
};

// Photons: positions apart (the grid indexes them), the rest alongside.
struct Photons {
    std::vector<Vec3> positions;
    std::vector<Photon> photons;
    void add(const Vec3& p, const Photon& photon) {
        positions.push_back(p);
        photons.push_back(photon);
    }
    // Empty, keeping the storage: a pass's photons reuse the last pass's memory.
    void clear() {
        positions.clear();
        photons.clear();
    }
    // Room for n photons, so that appending them does not grow by doubling. Growth leaves an
    // eighth spare, since the next pass's count differs by a little.
    void reserve(size_t n) {
        if (n <= photons.capacity()) return;
        positions.reserve(n + n / 8);
        photons.reserve(n + n / 8);
    }
    void append(const Photons& more) {
        positions.insert(positions.end(), more.positions.begin(), more.positions.end());
        photons.insert(photons.end(), more.photons.begin(), more.photons.end());
    }
};

// A pass's photons of one chunk of photon paths.
struct PhotonChunk {
    Photons surface, volume;
    void clear() {
        surface.clear();
        volume.clear();
    }
};

// One kind of estimate (on surfaces: 2D kernel; in media: 3D): its schedule, R_1, this pass's
// bandwidths and photons.
struct PhotonMap {
    ProgressiveBandwidths schedule;
    double requested_radius = 0;  // R_1 as given (0: the default)
    double radius_1 = 0;          // R_1 in use, set by preprocess()
    double radius2 = 0, bandwidth = 0;
    double ball = 1;   // kernel_ball_integral(spatial, schedule.dims)
    float radius = 0;  // R_j
    double norm = 0;   // 1 / (ball R_j^dims): the spatial kernel's normalisation
    Photons photons;
    PointGrid grid;

    // Sets the pass's bandwidths and indexes its photons.
    void begin(uint64_t pass, double bandwidth_1) {
        radius2 = schedule.radius_squared(radius_1 * radius_1, pass);
        bandwidth = schedule.time(bandwidth_1, pass);
        radius = float(std::sqrt(radius2));
        norm = 1.0 / (ball * std::pow(double(radius), schedule.dims));
        grid.build(photons.positions, radius);
    }
    // Calls each(photon, K_R) for every photon within R_j of x, K_R being the normalised
    // spatial kernel of `shape` at its distance.
    template <typename Each>
    void for_each_near(const Vec3& x, KernelShape shape, Each&& each) const {
        grid.query(x, [&](uint32_t i) {
            const Vec3 d = photons.positions[i] - x;
            const float dist2 = dot(d, d);
            if (!(dist2 < float(radius2))) return;
            each(photons.photons[i],
                 kernel_profile(shape, std::sqrt(double(dist2)) / radius) * norm);
        });
    }
};

// The camera path's state.
struct EyePath {
    Ray ray;
    PathClock clock;
    MediumTracker medium;
    Throughput throughput;
    int64_t depth = 1;
    DistanceMixtureCache free_paths{};  // mean-free-path distances, in the last medium
};

// Where a segment through a medium ended.
enum class SegmentEnd { Surface, Scattered, Stop };

class TransientPpm final : public MonteCarloIntegrator {
public:
    explicit TransientPpm(const Properties& props) : MonteCarloIntegrator(props, 5) {
        if (props.has("photons_per_pass")) {
            const int64_t photons = props.get_int("photons_per_pass");
            // 2^24 photon paths leave a few GB of photons per pass at most.
            if (photons < 1 || photons > (int64_t(1) << 24))
                props.fail("photons_per_pass", "photons_per_pass must lie in [1, 2^24]");
            requested_photons_ = uint64_t(photons);
        }
        surface_.schedule = read_progressive_schedule(props, "", 4.0 / 7.0, 1.0 / 3.0, 2);
        volume_.schedule = read_progressive_schedule(props, "volume_", 0.5, 0.25, 3);
        surface_.requested_radius = read_optional_bandwidth(props, "initial_radius");
        volume_.requested_radius = read_optional_bandwidth(props, "volume_initial_radius");
        initial_bandwidth_ = read_optional_bandwidth(props, "initial_bandwidth");
        spatial_ = read_kernel_shape(props, "spatial_kernel", "epanechnikov");
        temporal_ = read_kernel_shape(props, "temporal_kernel", "perlin");
        surface_.ball = kernel_ball_integral(spatial_, 2);
        volume_.ball = kernel_ball_integral(spatial_, 3);
    }

    uint32_t samples_per_pass() const override { return 1; }
    double time_reach() const override { return bandwidth_1_; }

    void preprocess(const Scene& scene) override {
        MonteCarloIntegrator::preprocess(scene);
        starts_.prepare(scene, "transient_ppm");
        require_histogram_film(scene, "transient_ppm");
        // By default one photon path per pixel, so that a pass's photon and camera halves cost
        // about the same (bench/README.md: more, shorter passes beat fewer, richer ones).
        const Film& film = scene.sensor().film();
        photons_per_pass_ =
            requested_photons_ > 0
                ? requested_photons_
                : std::max<uint64_t>(1024, uint64_t(film.width()) * uint64_t(film.height()));
        const double radius = default_initial_radius(scene);
        for (PhotonMap* map : {&surface_, &volume_})
            map->radius_1 = map->requested_radius > 0 ? map->requested_radius : radius;
        bandwidth_1_ =
            initial_bandwidth_ > 0 ? initial_bandwidth_ : default_initial_bandwidth(scene);
    }

    void begin_pass(const Scene& scene, const PassInfo& pass) override {
        trace_photons(scene, pass);
        surface_.begin(pass.pass, bandwidth_1_);
        volume_.begin(pass.pass, bandwidth_1_);
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& camera_ray,
                ContributionList& out) const override;

private:
    void trace_photons(const Scene& scene, const PassInfo& pass);
    bool eye_continues(Sampler& sampler, EyePath& eye, const Hit& hit, const Bsdf& bsdf) const;
    SegmentEnd eye_in_medium(Sampler& sampler, EyePath& eye, bool found, const Hit& hit) const;
    void gather(const Hit& hit, const Bsdf& bsdf, const EyePath& eye) const;
    void gather_volume(const Medium& medium, const EyePath& eye, const Color& weight) const;
    TimeKernel time_kernel(const PhotonMap& map) const {
        return TimeKernel{float(map.bandwidth), temporal_};
    }
    bool joins(int64_t eye_depth, const Photon& photon) const {
        return max_depth() < 0 || eye_depth + photon.depth <= max_depth();
    }

    uint64_t requested_photons_ = 0;  // photons_per_pass, 0 when not given
    uint64_t photons_per_pass_ = 0;   // what preprocess() settled on
    double initial_bandwidth_ = 0;    // 0: the default
    KernelShape spatial_ = KernelShape::Epanechnikov, temporal_ = KernelShape::Perlin;
    LightPathStarts starts_;
    double bandwidth_1_ = 0;           // T_1, set by preprocess()
    PhotonMap surface_, volume_;       // this pass's photons, read by sample()
    std::vector<PhotonChunk> chunks_;  // per chunk of photon paths, appended in order
};

// ---- camera paths ----------------------------------------------------------------------------

void TransientPpm::sample(const Scene& scene, Sampler& sampler, const Ray& camera_ray,
                          ContributionList& out) const {
    if (max_depth() == 0) return;
    EyePath eye{camera_ray, PathClock(scene, out, camera_ray.o), MediumTracker::at_sensor(scene),
                Throughput{}};
    Hit hit;  // one for every vertex: intersect() sets all of it
    for (;;) {
        const bool found = scene.intersect(eye.ray, hit);
        if (eye.medium.medium && eye_in_medium(sampler, eye, found, hit) != SegmentEnd::Surface)
            return;
        if (!found) {  // the environment, seen through delta bounces only (as emitters are)
            if (eye.depth > 1 || !hide_emitters())
                record_environment(scene, sampler, eye.clock, eye.throughput, eye.ray.d,
                                   eye.medium.eta(), 0.f, true);
            return;
        }
        const Bsdf& bsdf = *hit.shape->bsdf();
        eye.clock.travel_to(hit.p, eye.medium.eta());
        if (!bsdf.is_null()) eye.clock.reach_vertex();
        if (eye.clock.expired()) return;
        // Every vertex before this one was a delta bounce: emission is the path's to find.
        if (const Emitter* emitter = hit.shape->emitter())
            if (eye.depth > 1 || !hide_emitters())
                eye.clock.record(eye.throughput(emitter->eval(hit, -eye.ray.d)), *emitter, sampler);
        if (bsdf.is_null()) {  // an index-matched boundary: not a scattering event
            eye.medium.cross(hit, eye.ray.d);
            eye.ray = hit.spawn(eye.ray.d);
            continue;
        }
        if (depth_exhausted(eye.depth)) return;
        apply_vertex_event(bsdf, hit, sampler, eye.clock, eye.throughput);
        if (bsdf.flags() & kBsdfSmooth) gather(hit, bsdf, eye);
        if (!(bsdf.flags() & kBsdfDelta) || !eye_continues(sampler, eye, hit, bsdf)) return;
    }
}

// The camera ray crosses a medium toward `hit` (if `found`): a distance by the mean free path
// either ends the camera path at a medium vertex, where the volume photons estimate the
// in-scattered light, or reaches the surface with the segment's weight.
SegmentEnd TransientPpm::eye_in_medium(Sampler& sampler, EyePath& eye, bool found,
                                       const Hit& hit) const {
    const Medium& medium = *eye.medium.medium;
    const DistanceMixture& free_path = eye.free_paths(medium);
    const double tmax = found ? double(hit.t) : kInfinity;
    const double u = double(sampler.next_1d());
    const DistanceSample ds = sample_distance(medium, eye.ray, tmax, free_path, u, sampler);
    if (!ds.scattered) {
        eye.throughput *= ds.weight;
        return found && !eye.throughput.is_black() ? SegmentEnd::Surface : SegmentEnd::Stop;
    }
    eye.clock.travel_to(eye.ray.at(float(ds.distance)), medium.eta());
    eye.clock.reach_vertex();
    if (eye.clock.expired() || depth_exhausted(eye.depth)) return SegmentEnd::Stop;
    gather_volume(medium, eye, ds.weight);
    return SegmentEnd::Scattered;
}

// Continues the camera path through a delta lobe of `bsdf` (a smooth lobe's light is the
// gather's), then Russian roulette. Returns false when the path ends.
bool TransientPpm::eye_continues(Sampler& sampler, EyePath& eye, const Hit& hit,
                                 const Bsdf& bsdf) const {
    const float u_lobe = sampler.next_1d();
    const BsdfSample bs = bsdf.sample(hit, hit.wi, u_lobe, sampler.next_2d());
    if (!bs.valid() || !(bs.sampled_lobe & kBsdfDelta) || bs.weight.is_black()) return false;
    eye.throughput *= bs.weight;
    eye.medium.refract(bs);
    const Vec3 wo = hit.to_world(bs.wo);
    eye.medium.cross(hit, wo);
    eye.ray = hit.spawn(wo);
    const float survived = roulette(eye.depth, eye.throughput.max_gain(), sampler);
    if (survived == 0.f) return false;
    eye.throughput *= Color(survived);
    ++eye.depth;
    return true;
}

// The photon density estimate at the eye's surface vertex `hit` (eq. 5.54), each photon's
// light recorded at its own time with the temporal kernel.
void TransientPpm::gather(const Hit& hit, const Bsdf& bsdf, const EyePath& eye) const {
    const TimeKernel kernel = time_kernel(surface_);
    surface_.for_each_near(hit.p, spatial_, [&](const Photon& ph, double k) {
        if (!joins(eye.depth, ph)) return;
        const Vec3 wi = hit.to_local(ph.wi);
        // eval() is f |cos theta| in the shading frame; the photons' flux density needs f.
        const float cos_wi = std::abs(wi.z);
        if (!(cos_wi > 1e-6f)) return;
        const Color f = bsdf.eval(hit, hit.wi, wi);
        if (f.is_black()) return;
        eye.clock.record(eye.throughput(f * ph.power * float(k / cos_wi)), ph.time, kernel);
    });
}

// The volume photons' estimate of the light scattered toward the camera at the eye's medium
// vertex (the clock's position). The volume photons' density there is sigma_s times the
// radiance, so the sum over them, weighted by the phase function, is divided by sigma_s; the
// distance sample's `weight` (transmittance x sigma_s / pdf) loses that factor.
void TransientPpm::gather_volume(const Medium& medium, const EyePath& eye,
                                 const Color& weight) const {
    const Vec3 x = eye.clock.position(), wo = -eye.ray.d;
    const Color sigma_s = medium.sigma_s(x);
    auto per_density = [](float w, float s) { return s > 0.f ? w / s : 0.f; };
    Throughput throughput = eye.throughput;
    throughput *= Color(per_density(weight.r, sigma_s.r), per_density(weight.g, sigma_s.g),
                        per_density(weight.b, sigma_s.b));
    if (throughput.is_black()) return;
    const PhaseFunction& phase = medium.phase();
    const TimeKernel kernel = time_kernel(volume_);
    volume_.for_each_near(x, spatial_, [&](const Photon& ph, double k) {
        if (!joins(eye.depth, ph)) return;
        const float p = phase.eval(ph.wi, wo);
        if (!(p > 0.f)) return;
        eye.clock.record(throughput(ph.power * float(p * k)), ph.time, kernel);
    });
}

// ---- photon paths ----------------------------------------------------------------------------

// What a photon path leaves: a surface photon at every vertex with a smooth lobe, a volume
// photon at every medium vertex.
struct PhotonStore : PhotonVisitor {
    PhotonChunk& into;
    explicit PhotonStore(PhotonChunk& chunk) : into(chunk) {}
    void surface(const Hit& hit, const PhotonPath& path) {
        into.surface.add(hit.p, {-path.ray.d, path.power, path.clock.time(), int32_t(path.depth)});
    }
    void medium_vertex(const PhotonPath& path) {
        into.volume.add(path.clock.position(),
                        {-path.ray.d, path.power, path.clock.time(), int32_t(path.depth)});
    }
};

void TransientPpm::trace_photons(const Scene& scene, const PassInfo& pass) {
    // The last pass's photons are not needed while this pass's are traced; their storage,
    // and the chunks', is reused (bench/README.md: allocating it afresh every pass cost a
    // fifth of a render in page faults).
    surface_.photons.clear();
    volume_.photons.clear();
    const double scale = 1.0 / double(photons_per_pass_);
    trace_photon_paths(scene, pass, photons_per_pass_, chunks_,
                       [&](Sampler& sampler, PhotonChunk& into) {
                           PhotonStore store(into);
                           trace_photon_path(scene, starts_, *this, sampler, scale, store);
                       });
    size_t surface = 0, volume = 0;
    for (const PhotonChunk& chunk : chunks_)
        surface += chunk.surface.photons.size(), volume += chunk.volume.photons.size();
    surface_.photons.reserve(surface);
    volume_.photons.reserve(volume);
    for (const PhotonChunk& chunk : chunks_) {
        surface_.photons.append(chunk.surface);
        volume_.photons.append(chunk.volume);
    }
}

}  // namespace

FEMTO_PLUGIN(
    TransientPpm, femto::PluginKind::Integrator, "transient_ppm",
    "Transient progressive photon mapping on surfaces and in media (ch. 5.5.1, appendix 5.B): a "
    "spatio-temporal photon density estimate whose radius and time bandwidth shrink every pass",
    {{"photons_per_pass", "integer", "",
      "photon paths traced before each pass; default: the film's pixel count (at least 1024)"},
     {"alpha", "float", "0.571428",
      "share of each pass's bandwidth reduction kept (eq. 5.58); 4/7 "
      "minimises the asymptotic MSE"},
     {"beta_t", "float", "0.333333",
      "share of the reduction given to the time bandwidth (beta_R "
      "= 1 - beta_t; 1/3 is optimal)"},
     {"volume_alpha", "float", "0.5",
      "alpha of the volume photons' estimate (3D kernel); 1/2 minimises its asymptotic MSE"},
     {"volume_beta_t", "float", "0.25",
      "beta_t of the volume photons' estimate; 1/4 is optimal for a 3D kernel"},
     {"initial_radius", "float", "",
      "R_1 of the surface estimate (scene units); default: 3 pixel footprints at the "
      "image centre's first hit (or a mean free path away in a medium), at most 1/50 of the "
      "scene's bounding radius"},
     {"volume_initial_radius", "float", "",
      "R_1 of the volume photons' 3D kernel (scene units); default: as initial_radius's"},
     {"initial_bandwidth", "float", "",
      "T_1, half-width of the time kernel (scene units); "
      "default: 2 film bins"},
     {"spatial_kernel", "string", "epanechnikov", "K_R: box, epanechnikov, perlin or gaussian"},
     {"temporal_kernel", "string", "perlin", "K_T: box, epanechnikov, perlin or gaussian"},
     {"rr_depth", "integer", "5",
      "depth at which Russian roulette starts (photons and delta "
      "bounces of camera paths); 0 = never"}})
