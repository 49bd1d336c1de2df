// transient_ppm: transient progressive photon mapping on surfaces (thesis ch. 5.5.1 and
// appendix 5.B; Knaus & Zwicker's probabilistic PPM, which the appendix follows).
//
// Every pass (one iteration j = 1, 2, ...) does two things:
//   - begin_pass() traces `photons_per_pass` photon paths from the emitters, as the light
//     tracer's paths (pulses, delays, eta, adjoint shading factors), and stores a photon at
//     every surface vertex with a non-delta lobe: its position, incoming direction, power and
//     time (its LightClock's: emission time + optical length + delays), in a PointGrid;
//   - sample() follows each camera ray through delta bounces (mirrors, glass) to its first
//     vertex with a non-delta lobe and estimates the light leaving it toward the camera from
//     the photons within R_j (eq. 5.54): each photon i adds
//         throughput * f(wo, wi_i) * power_i * K_R(|x - x_i|)
//     at time t_eye + t_i spread by the temporal kernel K_T of half-width T_j, which the film
//     integrates exactly over its bins (Contribution::kernel). Emitters seen through delta
//     bounces are added as the path tracer adds them.
// The pixel estimate is the average over passes (eq. 5.55). Both bandwidths shrink with the
// pass (eq. 5.58, femto::ProgressiveBandwidths): T_j = T_1 s_j^beta_T and
// R_j^2 = R_1^2 s_j^(1 - beta_T), s_j = progressive_shrink(alpha, j - 1); alpha = 4/7 and
// beta_T = 1/3 minimise the AMSE (5.B.4).
//
// Film rule: the estimate smooths time with its own kernel, so a time-resolved film must use
// `<tfilter type="histogram"/>` (no second smoothing); steady films ignore time (ordinary PPM).
// Depth: a photon that reached its vertex after d_l segments joins an eye path of d_e segments
// only when d_e + d_l <= max_depth, so max_depth means what it means for transient_path.
// docs/photon-mapping.md derives the defaults of R_1 and T_1.
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "femto/integrator.h"
#include "femto/kernel.h"
#include "femto/path_clock.h"
#include "femto/plugin.h"
#include "femto/point_grid.h"
#include "femto/random.h"
#include "femto/sensor.h"
#include "femto/tfilter.h"
#include "femto/transport.h"

namespace {

using namespace femto;

// What a photon leaves at a surface vertex.
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
    void clear() {
        positions.clear();
        photons.clear();
    }
    void append(const Photons& more) {
        positions.insert(positions.end(), more.positions.begin(), more.positions.end());
        photons.insert(photons.end(), more.photons.begin(), more.photons.end());
    }
};

// Photon paths are traced in chunks of this many, each chunk's photons appended in chunk order,
// so that the map does not depend on the thread count.
constexpr uint64_t kPhotonChunk = 1024;

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
        schedule_.alpha = props.get_float("alpha", 4.0 / 7.0);
        if (!(schedule_.alpha > 0.0 && schedule_.alpha < 1.0))
            props.fail("alpha",
                       "alpha must lie in (0, 1): the share of each pass's "
                       "bandwidth reduction kept (eq. 5.58)");
        schedule_.beta_t = props.get_float("beta_t", 1.0 / 3.0);
        if (!(schedule_.beta_t >= 0.0 && schedule_.beta_t <= 1.0))
            props.fail("beta_t", "beta_t must lie in [0, 1] (beta_R = 1 - beta_t, eq. 5.58)");
        initial_radius_ = positive_or_default(props, "initial_radius");
        initial_bandwidth_ = positive_or_default(props, "initial_bandwidth");
        spatial_ = read_kernel_shape(props, "spatial_kernel", "epanechnikov");
        temporal_ = read_kernel_shape(props, "temporal_kernel", "perlin");
        spatial_norm_ = kernel_ball_integral(spatial_, 2);
    }

    uint32_t samples_per_pass() const override { return 1; }

    void preprocess(const Scene& scene) override {
        MonteCarloIntegrator::preprocess(scene);
        if (scene.has_media())
            throw SceneError(location(),
                             "transient_ppm estimates light on surfaces only; this scene has "
                             "participating media (use transient_path or transient_bdpt)");
        starts_.prepare(scene, "transient_ppm");
        require_histogram(scene);
        // By default one photon path per pixel, so that a pass's photon and camera halves cost
        // about the same (bench/README.md: more, shorter passes beat fewer, richer ones).
        const Film& film = scene.sensor().film();
        photons_per_pass_ =
            requested_photons_ > 0
                ? requested_photons_
                : std::max<uint64_t>(1024, uint64_t(film.width()) * uint64_t(film.height()));
        radius_1_ = initial_radius_ > 0 ? initial_radius_ : default_radius(scene);
        bandwidth_1_ = initial_bandwidth_ > 0 ? initial_bandwidth_ : default_bandwidth(scene);
    }

    void begin_pass(const Scene& scene, const PassInfo& pass) override {
        radius2_ = schedule_.radius_squared(radius_1_ * radius_1_, pass.pass);
        bandwidth_ = schedule_.time(bandwidth_1_, pass.pass);
        trace_photons(scene, pass);
        grid_.build(map_.positions, float(std::sqrt(radius2_)));
    }

    void sample(const Scene& scene, Sampler& sampler, const Ray& camera_ray,
                ContributionList& out) const override;

private:
    static double positive_or_default(const Properties& props, const char* name) {
        if (!props.has(name)) return 0.0;
        const double v = props.get_float(name);
        if (!(v > 0.0) || !std::isfinite(v))
            props.fail(name, fmt::format("{} must be positive and finite (scene units)", name));
        return v;
    }

    double default_radius(const Scene& scene) const;
    double default_bandwidth(const Scene& scene) const;
    static void require_histogram(const Scene& scene);
    void trace_photons(const Scene& scene, const PassInfo& pass);
    void trace_photon(const Scene& scene, Sampler& sampler, Photons& into) const;
    bool photon_useful(int64_t depth) const { return max_depth() < 0 || depth + 1 <= max_depth(); }
    void gather(const Hit& hit, const Bsdf& bsdf, const Throughput& throughput,
                const PathClock& clock, int64_t depth) const;

    uint64_t requested_photons_ = 0;  // photons_per_pass, 0 when not given
    uint64_t photons_per_pass_ = 0;   // what preprocess() settled on
    ProgressiveBandwidths schedule_;
    double initial_radius_ = 0, initial_bandwidth_ = 0;  // 0: the defaults
    KernelShape spatial_ = KernelShape::Epanechnikov, temporal_ = KernelShape::Perlin;
    double spatial_norm_ = 1;  // kernel_ball_integral(spatial_, 2)
    LightPathStarts starts_;
    // Set per render / per pass, read by sample().
    double radius_1_ = 0, bandwidth_1_ = 0;
    double radius2_ = 0, bandwidth_ = 0;
    Photons map_;                  // this pass's photons
    PointGrid grid_;               // over map_.positions
    std::vector<Photons> chunks_;  // per chunk of photon paths, appended to map_ in order
};

// ---- camera paths ----------------------------------------------------------------------------

void TransientPpm::sample(const Scene& scene, Sampler& sampler, const Ray& camera_ray,
                          ContributionList& out) const {
    if (max_depth() == 0) return;
    Ray ray = camera_ray;
    PathClock clock(scene, out, ray.o);
    MediumTracker medium = MediumTracker::at_sensor(scene);
    Throughput throughput;
    for (int64_t depth = 1;; ++depth) {
        Hit hit;
        if (!scene.intersect(ray, hit)) return;
        const Bsdf& bsdf = *hit.shape->bsdf();
        clock.travel_to(hit.p, medium.eta());
        if (!bsdf.is_null()) clock.reach_vertex();
        if (clock.expired()) return;
        // Every vertex before this one was a delta bounce: emission is the path's to find.
        if (const Emitter* emitter = hit.shape->emitter())
            if (depth > 1 || !hide_emitters())
                clock.record(throughput(emitter->eval(hit, -ray.d)), *emitter, sampler);
        if (bsdf.is_null()) {
            medium.cross(hit, ray.d);
            ray = hit.spawn(ray.d);
            --depth;  // not a scattering event
            continue;
        }
        if (depth_exhausted(depth)) return;
        apply_vertex_event(bsdf, hit, sampler, clock, throughput);
        const uint32_t flags = bsdf.flags();
        if (flags & kBsdfSmooth) gather(hit, bsdf, throughput, clock, depth);
        if (!(flags & kBsdfDelta)) return;
        // Continue through a delta lobe only; a smooth lobe's light is the gather's.
        const float u_lobe = sampler.next_1d();
        const BsdfSample bs = bsdf.sample(hit, hit.wi, u_lobe, sampler.next_2d());
        if (!bs.valid() || !(bs.sampled_lobe & kBsdfDelta) || bs.weight.is_black()) return;
        throughput *= bs.weight;
        medium.refract(bs);
        const Vec3 wo = hit.to_world(bs.wo);
        medium.cross(hit, wo);
        ray = hit.spawn(wo);
        if (rr_depth() > 0 && depth >= rr_depth()) {
            const float q = std::min(throughput.max_gain(), 0.95f);
            if (!(sampler.next_1d() < q)) return;
            throughput *= Color(1.f / q);
        }
    }
}

// The photon density estimate at the eye vertex `hit` (eq. 5.54), each photon's light
// recorded at its own time with the temporal kernel.
void TransientPpm::gather(const Hit& hit, const Bsdf& bsdf, const Throughput& throughput,
                          const PathClock& clock, int64_t depth) const {
    const float radius = float(std::sqrt(radius2_));
    const double norm = 1.0 / (spatial_norm_ * radius2_);
    const TimeKernel kernel{float(bandwidth_), temporal_};
    grid_.query(hit.p, [&](uint32_t i) {
        const Vec3 d = map_.positions[i] - hit.p;
        const float dist2 = dot(d, d);
        if (!(dist2 < float(radius2_))) return;
        const Photon& ph = map_.photons[i];
        if (max_depth() >= 0 && depth + ph.depth > max_depth()) return;
        const Vec3 wi = hit.to_local(ph.wi);
        // eval() is f |cos theta| in the shading frame; the photons' flux density needs f.
        const float cos_wi = std::abs(wi.z);
        if (!(cos_wi > 1e-6f)) return;
        const Color f = bsdf.eval(hit, hit.wi, wi);
        if (f.is_black()) return;
        const double k = kernel_profile(spatial_, std::sqrt(double(dist2)) / radius) * norm;
        clock.record(throughput(f * ph.power * float(k / cos_wi)), ph.time, kernel);
    });
}

// ---- photon paths ----------------------------------------------------------------------------

void TransientPpm::trace_photons(const Scene& scene, const PassInfo& pass) {
    const uint64_t chunks = (photons_per_pass_ + kPhotonChunk - 1) / kPhotonChunk;
    chunks_.resize(size_t(chunks));
    // Photon streams: another seed than the camera samples', the pass as the sample index.
    const uint64_t seed = mix64(pass.seed ^ 0x70686f746f6e73ull);
    const Sampler& prototype = scene.sensor().sampler();
    tbb::parallel_for(uint64_t(0), chunks, [&](uint64_t c) {
        std::unique_ptr<Sampler> sampler = prototype.clone();
        Photons& into = chunks_[size_t(c)];
        into.clear();
        const uint64_t end = std::min(photons_per_pass_, (c + 1) * kPhotonChunk);
        for (uint64_t i = c * kPhotonChunk; i < end; ++i) {
            sampler->start(seed, i, pass.pass);
            trace_photon(scene, *sampler, into);
        }
    });
    map_.clear();
    for (const Photons& chunk : chunks_) map_.append(chunk);
}

// One photon path: a photon at every vertex with a non-delta lobe, until the path ends (window,
// depth, roulette or escape).
void TransientPpm::trace_photon(const Scene& scene, Sampler& sampler, Photons& into) const {
    const LightPathStarts::Start start = LightPathStarts::sample(scene, sampler);
    if (!start) return;
    const EmissionSample& es = start.emission;
    LightClock clock(scene, *start.emitter, es.p, sampler);
    MediumTracker medium = starts_.medium(*start.emitter, es, es.d);
    Color power = start.power() * float(1.0 / double(photons_per_pass_));
    const float start_power = power.max_component();
    Ray ray = emission_ray(es);
    for (int64_t depth = 1; photon_useful(depth);) {
        Hit hit;
        if (!scene.intersect(ray, hit)) return;
        const Bsdf& bsdf = *hit.shape->bsdf();
        clock.travel_to(hit.p, medium.eta());
        if (clock.expired()) return;
        if (bsdf.is_null()) {
            medium.cross(hit, ray.d);
            ray = hit.spawn(ray.d);
            continue;
        }
        if (bsdf.flags() & kBsdfSmooth) {
            into.positions.push_back(hit.p);
            into.photons.push_back({-ray.d, power, clock.time(), int32_t(depth)});
        }
        if (!photon_useful(depth + 1)) return;
        const VertexEvent event = apply_vertex_event(bsdf, hit, sampler, clock);
        const float u_lobe = sampler.next_1d();
        const BsdfSample bs = bsdf.sample(hit, hit.wi, u_lobe, sampler.next_2d());
        if (!bs.valid() || bs.weight.is_black()) return;
        const Vec3 wo = hit.to_world(bs.wo);
        power = leaving(event, bs.weight * power) * adjoint_shading_factor(hit, -ray.d, wo);
        if (power.is_black()) return;
        medium.refract(bs);
        medium.cross(hit, wo);
        ray = hit.spawn(wo);
        if (rr_depth() > 0 && depth >= rr_depth()) {
            const float q = std::min(power.max_component() / start_power, 0.95f);
            if (!(sampler.next_1d() < q)) return;
            power *= 1.f / q;
        }
        ++depth;
    }
}

// ---- defaults --------------------------------------------------------------------------------

// R_1: three pixel footprints where the image centre's camera ray meets the scene (the
// distance between it and the next pixel's ray there), at most 1/50 of the scene's bounding
// radius; 1/500 of that radius when the centre ray escapes.
double TransientPpm::default_radius(const Scene& scene) const {
    const Film& film = scene.sensor().film();
    const Vec2 centre{0.5f * float(film.width()), 0.5f * float(film.height())};
    const Ray a = scene.sensor().sample_ray(centre, {0.5f, 0.5f});
    const Ray b = scene.sensor().sample_ray(centre + Vec2{1.f, 0.f}, {0.5f, 0.5f});
    const double extent = scene.bounds().radius();
    Ray probe = a;
    Hit hit;
    if (!scene.intersect(probe, hit)) return extent / 500.0;
    const double footprint = double(length(a.at(hit.t) - b.at(hit.t)));
    return std::clamp(3.0 * footprint, 1e-6 * extent, extent / 50.0);
}

// The estimate smooths time itself: a time-resolved film must not smooth a second time.
void TransientPpm::require_histogram(const Scene& scene) {
    const auto* film = dynamic_cast<const TimeResolvedFilm*>(&scene.sensor().film());
    if (film && !film->tfilter().is_histogram())
        throw SceneError(film->tfilter().location(),
                         fmt::format("transient_ppm smooths time with its own kernel "
                                     "(temporal_kernel, initial_bandwidth); the film must not "
                                     "smooth a second time: use <tfilter type=\"histogram\"/> "
                                     "instead of \"{}\"",
                                     film->tfilter().type_name()));
}

// T_1: two film bins (a steady film: the value does not matter, the kernel is ignored).
double TransientPpm::default_bandwidth(const Scene& scene) const {
    const auto* film = dynamic_cast<const TimeResolvedFilm*>(&scene.sensor().film());
    return film ? 2.0 * film->grid().bin_width : 1.0;
}

}  // namespace

FEMTO_PLUGIN(
    TransientPpm, femto::PluginKind::Integrator, "transient_ppm",
    "Transient progressive photon mapping on surfaces (ch. 5.5.1, appendix 5.B): a "
    "spatio-temporal photon density estimate whose radius and time bandwidth shrink every pass",
    {{"photons_per_pass", "integer", "",
      "photon paths traced before each pass; default: the film's pixel count (at least 1024)"},
     {"alpha", "float", "0.571428",
      "share of each pass's bandwidth reduction kept (eq. 5.58); 4/7 "
      "minimises the asymptotic MSE"},
     {"beta_t", "float", "0.333333",
      "share of the reduction given to the time bandwidth (beta_R "
      "= 1 - beta_t; 1/3 is optimal)"},
     {"initial_radius", "float", "",
      "R_1 (scene units); default: 3 pixel footprints at the "
      "image centre's first hit, at most 1/50 of the scene's bounding radius"},
     {"initial_bandwidth", "float", "",
      "T_1, half-width of the time kernel (scene units); "
      "default: 2 film bins"},
     {"spatial_kernel", "string", "epanechnikov", "K_R: box, epanechnikov, perlin or gaussian"},
     {"temporal_kernel", "string", "perlin", "K_T: box, epanechnikov, perlin or gaussian"},
     {"rr_depth", "integer", "5",
      "depth at which Russian roulette starts (photons and delta "
      "bounces of camera paths); 0 = never"}})
