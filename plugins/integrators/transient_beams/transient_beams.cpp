// transient_beams: transient progressive photon beams in participating media (thesis ch. 5.7;
// Jarosz et al. 2011, "A Comprehensive Theory of Volumetric Radiance Estimation Using Photon
// Points and Beams" and "Progressive Photon Beams"), the spatio-temporal progressive version
// that the thesis names as future work (5.8). docs/photon-beams.md derives it.
//
// Every pass (one iteration j = 1, 2, ...) does two things:
//   - begin_pass() traces `photons_per_pass` photon paths from the emitters (the light tracer's
//     paths, femto/photon_tracing.h) and keeps every segment they fly through a medium as a
//     beam: its start, direction, length (to the medium vertex where the path scattered, or to
//     the surface), the power that entered it, its clock's time at the start, its medium;
//   - sample() follows the camera path as a path tracer over surfaces (next-event estimation
//     and BSDF sampling with MIS, emitters it hits) but never scatters it in a medium: along
//     each segment through a medium it gathers the beams that pass within R_j of it instead
//     (beam x beam, 1D blur). A beam whose closest point x_b = b + t_b w_b lies at distance
//     `dist` from the camera segment's closest point x_c = o + t_c d adds
//         throughput * Tr_c(t_c) * sigma_s(x_c) * p(w_b -> -d) * power_b * Tr_b(t_b) / P_b(t_b)
//                    * K_R(dist) / sin(w_b, d)
//     at time t_eye(x_c) + t_b(x_b) (each eta-weighted) spread by the temporal kernel K_T of
//     half-width T_j, which the film integrates exactly over its bins. Tr_b / P_b is the
//     transmittance along the beam over the probability that its free flight passed t_b
//     (exp(-rate t_b)): the beam stops where its path scattered (a "short" beam), unbiased in
//     homogeneous and heterogeneous media (ratio-tracked Tr there). The camera segment then
//     goes on to its surface with its transmittance.
// Transport split: beams estimate all light scattered in a medium toward the camera path (its
// last medium vertex is the beam's); the camera path's surface vertices estimate the light
// reaching them from emitters, directly (light samples, emitter hits) or through further
// surface bounces. A path whose vertex nearest the camera, among all but the emitter's, lies in
// a medium is the beams'; one whose vertices there are all on surfaces is the path tracer's.
// The pixel estimate is the average over passes. Both bandwidths shrink with the pass (eq.
// 5.58 with a 1D spatial kernel, femto::ProgressiveBandwidths): T_j = T_1 s_j^beta_T,
// R_j = R_1 s_j^(1 - beta_T), s_j = progressive_shrink(alpha, j - 1); alpha = 2/3 and
// beta_T = 1/2 minimise the AMSE (docs/photon-mapping.md, the d = 1 row).
//
// Film rules: a time-resolved film must use `<tfilter type="histogram"/>` (the estimate smooths
// time itself) and record camera time: a world-time film subtracts one sensor distance per
// camera sample, while beams add light from every point of the camera ray. Steady films ignore
// time (ordinary progressive photon beams).

#include <algorithm>
#include <cmath>
#include <vector>

#include "beam_map.h"
#include "femto/density_estimation.h"
#include "femto/integrator.h"
#include "femto/kernel.h"
#include "femto/medium.h"
#include "femto/mis.h"
#include "femto/path_clock.h"
#include "femto/photon_tracing.h"
#include "femto/plugin.h"
#include "femto/sensor.h"
#include "femto/tfilter.h"
#include "femto/transport.h"

namespace {

using namespace femto;
using femto_beams::BeamMap;

// One segment of a photon path through a medium.
struct Beam {
    Vec3 origin, direction;
    double length;
    Color power;  // flux that entered the segment
    double time;  // its LightClock's time at the origin
    const Medium* medium;
    float rate;     // of its free flight: it passed t with probability exp(-rate t)
    int32_t depth;  // the segment's number along its path (1: leaves the emitter)
};

struct BeamChunk {
    std::vector<Beam> beams;
    void clear() { beams.clear(); }  // keeps the storage for the next pass
};

// Keeps every medium segment of a photon path.
struct BeamStore : PhotonVisitor {
    BeamChunk& into;
    explicit BeamStore(BeamChunk& chunk) : into(chunk) {}
    void medium_segment(const PhotonPath& path, const FreeFlight& flight) {
        if (!(flight.length > 0) || !std::isfinite(flight.length)) return;
        into.beams.push_back({path.ray.o, path.ray.d, flight.length, path.power, path.clock.time(),
                              flight.medium, float(flight.rate), int32_t(path.depth)});
    }
};

// The camera path's state.
struct EyePath {
    Ray ray;
    PathClock clock;
    MediumTracker medium;
    Throughput throughput;
    int64_t depth = 1;
    // For MIS of emitters the path hits: where its last direction was chosen, that choice's
    // density and whether it was a delta.
    Vec3 prev_p;
    float prev_pdf = 1.f;
    bool prev_delta = true;
};

// Where the camera line and a beam line come closest (unit directions).
struct ClosestApproach {
    double t_camera = 0, t_beam = 0, distance2 = 0, sin_angle = 0;
};

ClosestApproach closest_approach(const Vec3& o, const Vec3& d, const Beam& beam) {
    const double wx = double(o.x) - beam.origin.x, wy = double(o.y) - beam.origin.y,
                 wz = double(o.z) - beam.origin.z;
    const Vec3& e = beam.direction;
    const double b = double(d.x) * e.x + double(d.y) * e.y + double(d.z) * e.z;
    const double dw = d.x * wx + d.y * wy + d.z * wz, ew = e.x * wx + e.y * wy + e.z * wz;
    const double sin2 = std::max(0.0, 1.0 - b * b);
    ClosestApproach c;
    c.sin_angle = std::sqrt(sin2);
    if (sin2 < 1e-12) return c;  // parallel: the 1D blur is undefined (measure zero)
    c.t_camera = (b * ew - dw) / sin2;
    c.t_beam = (ew - b * dw) / sin2;
    const double rx = wx + d.x * c.t_camera - e.x * c.t_beam,
                 ry = wy + d.y * c.t_camera - e.y * c.t_beam,
                 rz = wz + d.z * c.t_camera - e.z * c.t_beam;
    c.distance2 = rx * rx + ry * ry + rz * rz;
    return c;
}

class TransientBeams final : public MonteCarloIntegrator {
public:
    explicit TransientBeams(const Properties& props)
        : MonteCarloIntegrator(props, 5), location_(props.location()) {
        if (props.has("photons_per_pass")) {
            const int64_t photons = props.get_int("photons_per_pass");
            if (photons < 1 || photons > (int64_t(1) << 24))
                props.fail("photons_per_pass", "photons_per_pass must lie in [1, 2^24]");
            requested_photons_ = uint64_t(photons);
        }
        schedule_ = read_progressive_schedule(props, "", 2.0 / 3.0, 0.5, 1);
        requested_radius_ = read_optional_bandwidth(props, "initial_radius");
        requested_bandwidth_ = read_optional_bandwidth(props, "initial_bandwidth");
        spatial_ = read_kernel_shape(props, "spatial_kernel", "epanechnikov");
        temporal_ = read_kernel_shape(props, "temporal_kernel", "perlin");
        segment_integral_ = kernel_ball_integral(spatial_, 1);
    }

    uint32_t samples_per_pass() const override { return 1; }
    double time_reach() const override { return bandwidth_1_; }

    void preprocess(const Scene& scene) override;

    void begin_pass(const Scene& scene, const PassInfo& pass) override {
        trace_beams(scene, pass);
        radius_ = std::sqrt(schedule_.radius_squared(radius_1_ * radius_1_, pass.pass));
        bandwidth_ = schedule_.time(bandwidth_1_, pass.pass);
        std::vector<Vec3> starts(beams_.size()), ends(beams_.size());
        for (size_t i = 0; i < beams_.size(); ++i) {
            starts[i] = beams_[i].origin;
            ends[i] = beams_[i].origin + beams_[i].direction * float(beams_[i].length);
        }
        map_.build(starts, ends, float(radius_));
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& camera_ray,
                ContributionList& out) const override;

private:
    void trace_beams(const Scene& scene, const PassInfo& pass);
    bool medium_segment(Sampler& sampler, EyePath& eye, bool found, const Hit& hit) const;
    void gather(Sampler& sampler, const EyePath& eye, double length) const;
    bool surface_vertex(const Scene& scene, Sampler& sampler, EyePath& eye, Hit& hit) const;
    void emitter_hit(const Scene& scene, Sampler& sampler, EyePath& eye, const Hit& hit,
                     const Emitter& emitter) const;
    void surface_light(const Scene& scene, Sampler& sampler, EyePath& eye, Hit& hit,
                       const Bsdf& bsdf) const;
    bool continue_from_surface(Sampler& sampler, EyePath& eye, const Hit& hit,
                               const Bsdf& bsdf) const;
    void check_film(const Scene& scene) const;

    SourceLocation location_;
    uint64_t requested_photons_ = 0, photons_per_pass_ = 0;
    ProgressiveBandwidths schedule_;
    double requested_radius_ = 0, requested_bandwidth_ = 0;  // 0: the defaults
    double radius_1_ = 0, bandwidth_1_ = 0;                  // R_1, T_1 in use
    double radius_ = 0, bandwidth_ = 0;                      // this pass's R_j, T_j
    KernelShape spatial_ = KernelShape::Epanechnikov, temporal_ = KernelShape::Perlin;
    double segment_integral_ = 2;  // kernel_ball_integral(spatial_, 1)
    LightPathStarts starts_;
    std::vector<BeamChunk> chunks_;
    std::vector<Beam> beams_;  // this pass's, read by sample()
    BeamMap map_;
};

void TransientBeams::preprocess(const Scene& scene) {
    MonteCarloIntegrator::preprocess(scene);
    if (!scene.has_media())
        throw SceneError(location_,
                         "transient_beams estimates light scattered in participating media, and "
                         "this scene has none (no shape bounds a <medium>, and neither the sensor "
                         "nor an emitter sits in one): use transient_path or transient_ppm");
    starts_.prepare(scene, "transient_beams");
    check_film(scene);
    const Film& film = scene.sensor().film();
    // By default one photon path per pixel, as transient_ppm (docs/photon-beams.md).
    photons_per_pass_ =
        requested_photons_ > 0
            ? requested_photons_
            : std::max<uint64_t>(1024, uint64_t(film.width()) * uint64_t(film.height()));
    radius_1_ = requested_radius_ > 0 ? requested_radius_ : default_initial_radius(scene);
    bandwidth_1_ =
        requested_bandwidth_ > 0 ? requested_bandwidth_ : default_initial_bandwidth(scene);
}

// ---- camera paths ----------------------------------------------------------------------------

void TransientBeams::sample(const Scene& scene, Sampler& sampler, const Ray& camera_ray,
                            ContributionList& out) const {
    if (max_depth() == 0) return;
    EyePath eye{camera_ray,
                PathClock(scene, out, camera_ray.o),
                MediumTracker::at_sensor(scene),
                Throughput{},
                1,
                camera_ray.o};
    Hit hit;  // one for every vertex: intersect() sets all of it
    for (;;) {
        const bool found = scene.intersect(eye.ray, hit);
        if (eye.medium.medium && !medium_segment(sampler, eye, found, hit)) return;
        if (!found) {  // the environment (MIS against the light samples)
            if (eye.depth > 1 || !hide_emitters())
                record_environment(scene, sampler, eye.clock, eye.throughput, eye.ray.d,
                                   eye.medium.eta(), eye.prev_pdf, eye.prev_delta);
            return;
        }
        if (!surface_vertex(scene, sampler, eye, hit)) return;
    }
}

// The camera segment crosses a medium toward `hit` (if `found`): the beams near it estimate
// the light scattered toward the camera along it; then its transmittance weighs what lies
// beyond. Returns false when nothing does (no surface, or all light absorbed).
bool TransientBeams::medium_segment(Sampler& sampler, EyePath& eye, bool found,
                                    const Hit& hit) const {
    const double length = found ? double(hit.t) : kInfinity;
    if (!depth_exhausted(eye.depth)) gather(sampler, eye, length);
    if (!found) return false;
    eye.throughput *= eye.medium.medium->transmittance(eye.ray, length, sampler);
    return !eye.throughput.is_black();
}

// The beam x beam estimate along the camera segment [0, length) (see the top of the file).
void TransientBeams::gather(Sampler& sampler, const EyePath& eye, double length) const {
    thread_local std::vector<uint32_t> found;
    const Vec3 &o = eye.ray.o, &d = eye.ray.d;
    map_.query(o, d, length, found);
    if (found.empty()) return;
    const Medium& medium = *eye.medium.medium;
    const PhaseFunction& phase = medium.phase();
    const double radius2 = radius_ * radius_;
    const double norm = 1.0 / (segment_integral_ * radius_);
    const TimeKernel kernel{float(bandwidth_), temporal_};
    for (const uint32_t i : found) {
        const Beam& beam = beams_[i];
        if (beam.medium != &medium) continue;  // a beam just across a boundary
        if (max_depth() >= 0 && eye.depth + beam.depth > max_depth()) continue;
        const ClosestApproach c = closest_approach(o, d, beam);
        if (!(c.distance2 < radius2) || c.t_camera < 0 || !(c.t_camera < length) || c.t_beam < 0 ||
            c.t_beam > beam.length)
            continue;
        const float p = phase.eval(-beam.direction, -d);
        if (!(p > 0.f)) continue;
        const Vec3 x = eye.ray.at(float(c.t_camera));
        const Color sigma_s = medium.sigma_s(x);
        if (sigma_s.is_black()) continue;
        const double k = kernel_profile(spatial_, std::sqrt(c.distance2) / radius_) * norm;
        const Ray along_beam{beam.origin, beam.direction, 0.f, kInfinity};
        const Color beam_light = beam.power * medium.transmittance(along_beam, c.t_beam, sampler) *
                                 float(std::exp(double(beam.rate) * c.t_beam));
        const Color camera = medium.transmittance(eye.ray, c.t_camera, sampler);
        const Color value = beam_light * camera * sigma_s * float(p * k / c.sin_angle);
        PathClock at_x = eye.clock;
        at_x.travel_to(x, medium.eta());
        at_x.record(eye.throughput(value), beam.time + medium.eta() * c.t_beam, kernel);
    }
}

// ---- surfaces: a path tracer's ----------------------------------------------------------------

// The camera path reaches surface `hit`. Returns false when it ends there.
bool TransientBeams::surface_vertex(const Scene& scene, Sampler& sampler, EyePath& eye,
                                    Hit& hit) const {
    const Bsdf& bsdf = *hit.shape->bsdf();
    eye.clock.travel_to(hit.p, eye.medium.eta());
    if (!bsdf.is_null()) eye.clock.reach_vertex();
    if (eye.clock.expired()) return false;
    if (const Emitter* emitter = hit.shape->emitter())
        emitter_hit(scene, sampler, eye, hit, *emitter);
    if (bsdf.is_null()) {  // an index-matched boundary: not a scattering event
        eye.medium.cross(hit, eye.ray.d);
        eye.ray = hit.spawn(eye.ray.d);
        return true;
    }
    if (depth_exhausted(eye.depth)) return false;
    apply_vertex_event(bsdf, hit, sampler, eye.clock, eye.throughput);
    if (bsdf.flags() & kBsdfSmooth) surface_light(scene, sampler, eye, hit, bsdf);
    return continue_from_surface(sampler, eye, hit, bsdf);
}

// Emission seen by the path, weighted by MIS against the light sample that could have found it
// from the previous surface vertex.
void TransientBeams::emitter_hit(const Scene& scene, Sampler& sampler, EyePath& eye, const Hit& hit,
                                 const Emitter& emitter) const {
    const Color Le = emitter.eval(hit, -eye.ray.d);
    if (Le.is_black() || (eye.depth == 1 && hide_emitters())) return;
    const float w =
        eye.prev_delta ? 1.f
                       : power_heuristic(eye.prev_pdf, scene.pdf_emitter(emitter, eye.prev_p, hit));
    eye.clock.record(eye.throughput(Le * w), emitter, sampler);
}

// Next-event estimation at a surface: one light sample and its shadow connection, through
// media with their transmittance; the light arrives over the connection's optical length.
void TransientBeams::surface_light(const Scene& scene, Sampler& sampler, EyePath& eye, Hit& hit,
                                   const Bsdf& bsdf) const {
    const EmitterSample light = sample_emitter(scene, hit, sampler);
    if (!(light.pdf > 0) || light.weight.is_black()) return;
    const Vec3 wo = hit.to_local(light.wi);
    const Color f = bsdf.eval(hit, hit.wi, wo);
    if (f.is_black()) return;
    const ShadowConnection c = connect_to_light(scene, hit, light, eye.medium, sampler);
    if (c.blocked()) return;
    const float w = light.delta ? 1.f : power_heuristic(light.pdf, bsdf.pdf(hit, hit.wi, wo));
    eye.clock.record(eye.throughput(f * light.weight * c.transmittance * w), *light.emitter,
                     sampler, c.optical_length);
}

// Samples the BSDF for the next direction, then Russian roulette. Returns false when the path
// ends.
bool TransientBeams::continue_from_surface(Sampler& sampler, EyePath& eye, const Hit& hit,
                                           const Bsdf& bsdf) const {
    const float u_lobe = sampler.next_1d();
    const BsdfSample bs = bsdf.sample(hit, hit.wi, u_lobe, sampler.next_2d());
    if (!bs.valid() || bs.weight.is_black()) return false;
    eye.throughput *= bs.weight;
    eye.medium.refract(bs);
    eye.prev_delta = (bs.sampled_lobe & kBsdfDelta) != 0;
    eye.prev_pdf = bs.pdf;
    eye.prev_p = hit.p;
    const Vec3 wo = hit.to_world(bs.wo);
    eye.medium.cross(hit, wo);
    eye.ray = hit.spawn(wo);
    const float survived = roulette(eye.depth, eye.throughput.max_gain(), sampler);
    if (survived == 0.f) return false;
    eye.throughput *= Color(survived);
    ++eye.depth;
    return true;
}

// ---- beams -----------------------------------------------------------------------------------

void TransientBeams::trace_beams(const Scene& scene, const PassInfo& pass) {
    // The last pass's beams are not needed while this pass's are traced.
    map_.release();
    beams_.clear();  // keeps the storage: allocating it afresh every pass costs page faults
    const double scale = 1.0 / double(photons_per_pass_);
    trace_photon_paths(scene, pass, photons_per_pass_, chunks_,
                       [&](Sampler& sampler, BeamChunk& into) {
                           BeamStore store(into);
                           trace_photon_path(scene, starts_, *this, sampler, scale, store);
                       });
    size_t count = 0;
    for (const BeamChunk& chunk : chunks_) count += chunk.beams.size();
    if (count > beams_.capacity()) beams_.reserve(count + count / 8);
    for (const BeamChunk& chunk : chunks_)
        beams_.insert(beams_.end(), chunk.beams.begin(), chunk.beams.end());
}

// ---- defaults and checks ---------------------------------------------------------------------

// A time-resolved film must not smooth a second time, and must record camera time.
void TransientBeams::check_film(const Scene& scene) const {
    require_histogram_film(scene, "transient_beams");
    const auto* film = dynamic_cast<const TimeResolvedFilm*>(&scene.sensor().film());
    if (film && film->world_time())
        throw SceneError(location_,
                         "transient_beams adds light from every point along a camera ray, while "
                         "a world-time film removes one sensor distance per camera sample: use "
                         "world_time=false (camera time) with this integrator");
}

}  // namespace

FEMTO_PLUGIN(
    TransientBeams, femto::PluginKind::Integrator, "transient_beams",
    "Transient progressive photon beams in participating media (ch. 5.7): photon paths' medium "
    "segments gathered along camera rays with a 1D blur and a time kernel that shrink every "
    "pass; surfaces by path tracing with next-event estimation",
    {{"photons_per_pass", "integer", "",
      "photon paths traced before each pass (each leaves a beam per medium segment); "
      "default: the film's pixel count (at least 1024)"},
     {"alpha", "float", "0.666667",
      "share of each pass's bandwidth reduction kept (eq. 5.58); 2/3 minimises the "
      "asymptotic MSE of the 1D blur with a time kernel"},
     {"beta_t", "float", "0.5",
      "share of the reduction given to the time bandwidth (beta_R = 1 - beta_t; 1/2 is "
      "optimal for the 1D blur)"},
     {"initial_radius", "float", "",
      "R_1, the beams' blur radius (scene units); default: 3 pixel footprints a mean free "
      "path into the sensor's medium (or at the image centre's first hit), at most 1/50 of "
      "the scene's bounding radius"},
     {"initial_bandwidth", "float", "",
      "T_1, half-width of the time kernel (scene units); default: 2 film bins"},
     {"spatial_kernel", "string", "epanechnikov",
      "K_R across beams: box, epanechnikov, perlin or gaussian"},
     {"temporal_kernel", "string", "perlin", "K_T: box, epanechnikov, perlin or gaussian"},
     {"rr_depth", "integer", "5",
      "depth at which Russian roulette starts (photon paths and camera paths); 0 = never"}})
