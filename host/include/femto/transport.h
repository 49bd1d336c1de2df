// femto public API: the transport toolkit, the building blocks an estimator is made of
// (docs/writing-plugins.md walks through them in the order an integrator meets them):
//   - Throughput: a path's weight, including vertex events that move energy between colour
//     channels (fluorescence), and apply_vertex_event(), which also gives the clock the delay;
//   - MediumTracker: the medium a path travels in and the refractive index outside media;
//   - sample_emitter(): a light sample drawn in femto's order of random numbers;
//   - connect_to_light(): the shadow connection to it, through null boundaries and media, with
//     its transmittance and eta-weighted optical length;
//   - DistanceMixture and sample_distance(): the distance strategy in a medium (ch. 5.6.1),
//     alone or MIS-combined with mean-free-path sampling; DistanceMixtureCache keeps the
//     last medium's;
//   - SegmentDensities: a segment's distance densities seen from either end, for the MIS
//     weights of bidirectional estimators (shadow connections report their MediumPieces);
//   - connection_reach(): how far along a segment a connection strategy's vertex may lie and
//     still reach its light within the film's window (eq. 5.110-5.111);
//   - light paths: LightPathStarts (where they start and in which medium), emission_ray(),
//     apply_vertex_event() with a LightClock and leaving(), adjoint_shading_factor(), and
//     connect_to_sensor() to splat what the camera sees of them.
// The time rules themselves are PathClock's and LightClock's (femto/path_clock.h); the MIS
// weights are in femto/mis.h. `plugins/integrators/path` is an estimator written with these
// pieces, `plugins/integrators/transient_light` and `transient_bdpt` the light-path ones.
#pragma once

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "femto/bsdf.h"
#include "femto/color.h"
#include "femto/emitter.h"
#include "femto/medium.h"
#include "femto/mis.h"
#include "femto/path_clock.h"
#include "femto/sampler.h"
#include "femto/scene.h"
#include "femto/sensor.h"
#include "femto/time_sampling.h"

namespace femto {

// ---- path weight -----------------------------------------------------------------------------

/// The weight a path applies to light arriving at its current vertex: a colour per channel
/// (diag(colour)) until a vertex event moves energy between channels, then mix * diag(colour).
/// The fast diagonal form is kept as long as possible.
class Throughput {
public:
    /// The weighted value of light `c` arriving at the current vertex.
    Color operator()(const Color& c) const { return mixing_ ? mix_ * (colour_ * c) : colour_ * c; }
    Throughput& operator*=(const Color& c) {
        colour_ *= c;
        return *this;
    }
    /// Applies a vertex event's colour transfer (VertexEvent::transfer).
    void transfer(const ColorMatrix& t);
    /// True when no light can pass any more (the per-channel weight is zero).
    bool is_black() const { return colour_.is_black(); }
    /// The most the path can carry into any one channel of unit white light: the survival
    /// probability Russian roulette uses.
    float max_gain() const {
        return mixing_ ? mix_.scale_columns(colour_).max_row_sum() : colour_.max_component();
    }

private:
    Color colour_{1.f, 1.f, 1.f};
    ColorMatrix mix_;  // identity (and unused) until a non-diagonal transfer
    bool mixing_ = false;
};

/// Samples the vertex event of a surface whose material has one (fluorescence, eq. 5.13): its
/// delay goes to the clock and its colour transfer to the throughput; everything leaving the
/// vertex, its light samples included, carries both. Draws one number when it has one.
inline void apply_vertex_event(const Bsdf& bsdf, const Hit& hit, Sampler& sampler, PathClock& clock,
                               Throughput& throughput) {
    if (!bsdf.has_vertex_event()) return;
    const VertexEvent event = bsdf.sample_vertex_event(hit, sampler.next_1d());
    clock.delay(event.delay);
    if (event.transfers) throughput.transfer(event.transfer);
}

/// The same for a light path: the event's delay goes to the light path's clock, and the event
/// is returned, since its colour transfer applies to the light that leaves the vertex
/// (leaving()), not to a throughput. Draws one number when the material has an event; an
/// ordinary material gives the identity event.
inline VertexEvent apply_vertex_event(const Bsdf& bsdf, const Hit& hit, Sampler& sampler,
                                      LightClock& clock) {
    if (!bsdf.has_vertex_event()) return {};
    const VertexEvent event = bsdf.sample_vertex_event(hit, sampler.next_1d());
    clock.delay(event.delay);
    return event;
}

/// Light leaving a vertex whose event transfers colour: transfer x light (light paths carry
/// light, so the transfer applies after the BSDF's colour, in the light's direction).
inline Color leaving(const VertexEvent& event, const Color& light) {
    return event.transfers ? event.transfer * light : light;
}

// ---- media -----------------------------------------------------------------------------------

/// The medium a path travels in (null: none) and the refractive index outside media, which
/// transmissions through dielectrics change. Time runs at eta() along the current segment.
struct MediumTracker {
    const Medium* medium = nullptr;
    double index = 1.0;

    /// Starts where the sensor sits.
    static MediumTracker at_sensor(const Scene& scene) { return {scene.sensor().medium(), 1.0}; }
    /// Refractive index along the current segment.
    double eta() const { return medium ? medium->eta() : index; }
    /// The medium beyond `hit`'s surface for a path leaving it in direction d: a shape that
    /// bounds no medium leaves it unchanged; otherwise the side d points to decides (the
    /// geometric normal points to the exterior).
    const Medium* beyond(const Hit& hit, const Vec3& d) const {
        const Shape& shape = *hit.shape;
        if (!shape.has_media()) return medium;
        return dot(d, hit.ng) < 0 ? shape.interior() : shape.exterior();
    }
    /// The path crosses `hit`'s surface in direction d.
    void cross(const Hit& hit, const Vec3& d) { medium = beyond(hit, d); }
    /// A BSDF sample that transmits through a dielectric changes the index outside media by
    /// the sample's relative index (BsdfSample::eta).
    void refract(const BsdfSample& bs) {
        if (bs.sampled_lobe &
            (kBsdfDeltaTransmission | kBsdfGlossyTransmission | kBsdfDiffuseTransmission))
            index *= double(bs.eta);
    }
};

// ---- light sampling and shadow connections ---------------------------------------------------

/// One light sample for next-event estimation at `ref`: the emitter is chosen with the first
/// number, the point on it with the next two (Scene::sample_emitter).
inline EmitterSample sample_emitter(const Scene& scene, const Vec3& ref, Sampler& sampler) {
    const float u_select = sampler.next_1d();
    return scene.sample_emitter(ref, u_select, sampler.next_2d());
}

/// The half-angle of light directions `light` stands for over a camera ray's pixel footprint
/// at `p` (PixelFootprint::light_cone): the cone the emitter subtends there, plus half the
/// turn of the direction toward a light at finite distance across the pixel (the
/// perpendicular part of the footprint's step over the distance). At most pi.
inline float footprint_light_cone(const PixelFootprint& f, const Vec3& p,
                                  const EmitterSample& light) {
    float cone = light.emitter ? light.emitter->subtended_half_angle(p) : 0.f;
    if (light.emitter && !light.emitter->is_infinite() && light.distance > 0.f) {
        auto turn = [&](const Vec3& dp) {
            return length(dp - light.wi * dot(dp, light.wi)) / light.distance;
        };
        cone += 0.5f * std::max(turn(f.dp_dx), turn(f.dp_dy));
    }
    return std::min(cone, kPi);
}

/// sample_emitter() at a surface hit: when a camera ray found it (hit.footprint.valid), also
/// sets hit.footprint.light_cone for the sample, so that a prefiltering material (btf)
/// evaluated toward the light, and then sampled to continue the path, filters over the light
/// directions the pixel sees. Other materials ignore it.
inline EmitterSample sample_emitter(const Scene& scene, Hit& hit, Sampler& sampler) {
    const EmitterSample light = sample_emitter(scene, hit.p, sampler);
    if (hit.footprint.valid)
        hit.footprint.light_cone = footprint_light_cone(hit.footprint, hit.p, light);
    return light;
}

/// Receives the pieces a shadow connection crosses between boundaries, in order from the
/// connection's start (`medium` null in vacuum): a bidirectional integrator weighs its
/// strategies with the distance densities of these pieces (SegmentDensities).
class MediumPieces {
public:
    /// The next piece. Returns the transmittance over it where the listener's own work found
    /// it (DistanceMixture::transmittance()): trace_shadow() then does not ask the
    /// medium again. std::nullopt otherwise, and in vacuum.
    virtual std::optional<Color> piece(const Medium* medium, double length) = 0;

protected:
    ~MediumPieces() = default;
};

/// What light loses and how long it takes along a shadow connection.
struct ShadowConnection {
    Color transmittance{1.f, 1.f, 1.f};  ///< black when something opaque blocks it
    double optical_length = 0.0;         ///< eta-weighted length (add it to the clock's time)
    bool blocked() const { return transmittance.is_black(); }
};

/// The shadow ray `ray` (from ray.o to ray.o + ray.d * ray.tmax) starting in `medium`: passes
/// null surfaces (media boundaries), changing media there, and multiplies each medium's
/// transmittance; blocked at any other surface. `from` and `to` are the connection's actual
/// end points (the ray starts off a surface and stops short of the light): the optical length
/// is measured between them and the boundaries crossed. `pieces`, when given, hears of every
/// medium piece of the connection (of all of it, so it is only meaningful when not blocked).
/// With `through_masks` the ray also crosses every other surface, its transmittance multiplied
/// by the surface's Bsdf::null_transmission() (0 blocks it): for estimators whose connections
/// are the only way light crosses that segment (light tracing). Estimators that also sample
/// a `mask`'s null lobe along the same segment (path tracing with light samples, BDPT) must
/// leave it false, or they would count that light twice.
ShadowConnection trace_shadow(const Scene& scene, Ray ray, const Vec3& from, const Vec3& to,
                              MediumTracker medium, Sampler& sampler,
                              MediumPieces* pieces = nullptr, bool through_masks = false);

/// The shadow connection from surface vertex `from` to light sample `light`. Without media in
/// the scene it is an occlusion test and light crosses `light.distance` in vacuum (a shadow
/// ray cannot leave a dielectric: its surface blocks it).
ShadowConnection connect_to_light(const Scene& scene, const Hit& from, const EmitterSample& light,
                                  const MediumTracker& medium, Sampler& sampler,
                                  MediumPieces* pieces = nullptr);

/// The shadow connection from a point `x` inside `medium.medium` to light sample `light`.
ShadowConnection connect_to_light(const Scene& scene, const Vec3& x, const EmitterSample& light,
                                  const MediumTracker& medium, Sampler& sampler,
                                  MediumPieces* pieces = nullptr);

/// A camera path's ray `d` left the scene from the clock's vertex, in vacuum or a medium of
/// index `eta` (in a medium with no surface ahead nothing comes through; do not call it
/// then): records the light of every environment emitter arriving along it, at its time
/// (PathClock::record_distant), times `throughput`. Each is weighted by MIS (power heuristic)
/// against the light sample that could have picked the same direction at the previous vertex,
/// which chose d with solid-angle density `prev_pdf`; after a delta choice (`prev_delta`) the
/// weight is 1. `share` scales the weights (the part of the direct light this strategy keeps).
inline void record_environment(const Scene& scene, Sampler& sampler, const PathClock& clock,
                               const Throughput& throughput, const Vec3& d, double eta,
                               float prev_pdf, bool prev_delta, float share = 1.f) {
    for (const Emitter* env : scene.environment()) {
        const float w =
            prev_delta ? 1.f : share * power_heuristic(prev_pdf, scene.pdf_environment(*env, d));
        clock.record_distant(throughput(env->eval_environment(d) * w), *env, sampler, d, eta);
    }
}

// ---- light paths -----------------------------------------------------------------------------

/// The medium at point `p` as a camera path would find it: the sensor's medium, changed at
/// every surface with media (MediumTracker::cross) on the straight line from the sensor to p.
/// (Paths track media from the sensor; emitters rarely name the medium they sit in.)
MediumTracker medium_at(const Scene& scene, const Vec3& p);

/// The medium light leaving emission sample `es` of `emitter` in direction `d` travels in
/// (refractive index 1 outside media): an area emitter's shape's medium on the side d points
/// to when the shape bounds media, else the emitter's own medium if it names one, else
/// `surrounding` (e.g. medium_at() the emitter, found once).
MediumTracker medium_at_emission(const Emitter& emitter, const EmissionSample& es, const Vec3& d,
                                 const Medium* surrounding);

/// Where light paths start, for integrators that trace them: prepare() checks that every
/// emitter samples its emission (a located SceneError naming `integrator` otherwise) and finds
/// once the medium around each emitter that names none (medium_at() a point just off it).
class LightPathStarts {
public:
    void prepare(const Scene& scene, const std::string& integrator);

    /// Where a light path starts: its emitter, the probability of choosing it, and the point
    /// and direction sampled on it.
    struct Start {
        const Emitter* emitter = nullptr;  ///< null: no start (no emitters, or sampling failed)
        float pmf = 0.f;
        EmissionSample emission;
        /// The light the path carries on its first segment: emission.weight / pmf.
        Color power() const { return emission.weight / pmf; }
        explicit operator bool() const { return emitter != nullptr; }
    };
    /// Chooses an emitter with one number (Scene::select_emitter) and samples its emission with
    /// four more (point, then direction), in this order.
    static Start sample(const Scene& scene, Sampler& sampler);

    /// The medium light leaving emission sample `es` of `emitter` in direction `d` travels in.
    MediumTracker medium(const Emitter& emitter, const EmissionSample& es, const Vec3& d) const;
    /// Whether `emitter` sends its light in a single direction (collimated), as its emission
    /// samples say.
    bool delta_direction(const Emitter& emitter) const;

private:
    struct Known {
        const Emitter* emitter;
        const Medium* surrounding;
        bool delta_direction;
    };
    const Known* find(const Emitter& emitter) const;
    std::vector<Known> emitters_;
};

/// The first ray of a light path: from es.p (off its surface by es.p_error) along es.d.
inline Ray emission_ray(const EmissionSample& es) {
    const Vec3 o = es.p_error > 0 ? offset_origin(es.p, es.n, es.d, es.p_error) : es.p;
    return Ray{o, es.d, 0.f, kInfinity};
}

/// The connection from surface vertex `from` to the sensor point of `sensor` (a light path
/// seen by the camera), as connect_to_light() traces it: its transmittance and optical length
/// (the splat's sensor distance).
/// `through_masks`: as trace_shadow()'s (a light tracer's connections pass partly transparent
/// surfaces, weighted by their null transmission).
ShadowConnection connect_to_sensor(const Scene& scene, const Hit& from, const SensorSample& sensor,
                                   const MediumTracker& medium, Sampler& sampler,
                                   MediumPieces* pieces = nullptr, bool through_masks = false);
/// The same from a point `x` inside `medium.medium` or, with p_error > 0, on a surface of
/// geometric normal `n` (an emitter's point: EmissionSample::n and p_error).
ShadowConnection connect_to_sensor(const Scene& scene, const Vec3& x, const SensorSample& sensor,
                                   const MediumTracker& medium, Sampler& sampler,
                                   const Vec3& n = Vec3(), float p_error = 0.f,
                                   MediumPieces* pieces = nullptr, bool through_masks = false);

/// Light paths see shading normals differently from camera paths (Veach 1997, sec. 5.3.2):
/// a BSDF weight (eval() or a sample's weight, which use the shading cosine of `wo`) for light
/// arriving at `hit` from world direction `wi` and leaving toward `wo` is multiplied by
/// |wi.ns| |wo.ng| / (|wi.ng| |wo.ns|); 0 when wi grazes the geometric surface.
inline float adjoint_shading_factor(const Hit& hit, const Vec3& wi, const Vec3& wo) {
    const float num = std::abs(dot(wi, hit.sh.n)) * std::abs(dot(wo, hit.ng));
    const float den = std::abs(dot(wi, hit.ng)) * std::abs(dot(wo, hit.sh.n));
    return den > 0.f ? num / den : 0.f;
}

// ---- distance sampling in media (ch. 5.6.1) -------------------------------------------------

/// The distance strategy in one medium: an exponential at the strategy's rate (mean free path
/// when there is none), or, with `mis`, a half-half mixture of it and the mean-free-path
/// exponential (one-sample MIS, balance heuristic). The rate does not depend on the direction,
/// so a distance may be drawn before the direction it will be travelled in (time angular
/// sampling needs that).
class DistanceMixture {
public:
    DistanceMixture(const Medium& medium, const DistanceSampler* strategy, bool mis,
                    const DistanceContext& ctx)
        : DistanceMixture(DistanceSampler::mean_free_path(medium), medium, strategy, mis, ctx) {}

    /// A distance from one uniform number (+infinity when the rate is zero).
    double sample(double u) const {
        double rate = strategy_;
        if (mix_) {  // pick one of the two exponentials with probability 1/2, reusing u
            rate = u < 0.5 ? steady_ : strategy_;
            u = u < 0.5 ? 2 * u : 2 * u - 1;
        }
        return rate > 0.0 ? DistanceSampler::sample(rate, std::min(u, 1.0 - 1e-12)) : kInfinity;
    }
    /// Density of sample() returning r.
    double pdf(double r) const { return at(r).pdf; }
    /// The mean-free-path rate (DistanceSampler::mean_free_path_rate(); the only rate when
    /// there is no strategy).
    double steady_rate() const { return steady_; }
    /// Probability that sample() returns more than d.
    double survival(double d) const { return at(d).survival; }
    /// survival(d) and pdf(d) together, from one exponential per rate (an exponential's density
    /// is its rate times its survival; a segment's densities need both, and exp() was a tenth
    /// of BDPT's time in fog).
    struct AtDistance {
        double survival, pdf;
    };
    AtDistance at(double d) const {
        const double e_strategy = DistanceSampler::survival(strategy_, d);
        if (!mix_) return {e_strategy, strategy_ * e_strategy};
        const double e_steady = DistanceSampler::survival(steady_, d);
        return {0.5 * (e_steady + e_strategy), 0.5 * (steady_ * e_steady + strategy_ * e_strategy)};
    }
    /// True when survival(d) is the medium's transmittance over d: mean-free-path distances
    /// alone in a homogeneous medium whose extinction is the same in every channel (its rate is
    /// that extinction, and Medium::homogeneous() promises exp(-sigma_t d)). A shadow
    /// connection that needs both then takes one exponential instead of two.
    bool survival_is_transmittance() const { return survival_is_transmittance_; }
    /// The medium's transmittance over the distance `at` was found at, from its survival, where
    /// survival_is_transmittance() (rounded to float per channel, as a homogeneous medium's
    /// transmittance() is); std::nullopt elsewhere.
    std::optional<Color> transmittance(const AtDistance& at) const {
        if (!survival_is_transmittance_) return std::nullopt;
        return Color(float(at.survival));
    }

private:
    // (The medium is looked at once: a mixture is made per medium and per sample.)
    DistanceMixture(const DistanceSampler::MeanFreePath& steady, const Medium& medium,
                    const DistanceSampler* strategy, bool mis, const DistanceContext& ctx)
        : steady_(steady.rate),
          strategy_(strategy ? strategy->rate(medium, ctx) : steady_),
          mix_(mis && strategy && strategy_ != steady_),
          survival_is_transmittance_(!mix_ && strategy_ == steady_ && steady.grey_homogeneous) {}

    double steady_, strategy_;
    bool mix_;
    bool survival_is_transmittance_;
};

/// The angular strategy at a medium vertex (ch. 5.6.3): a direction by `strategy` alone, or,
/// with `mis`, from a half-half mixture of it and the phase function (one-sample MIS, balance
/// heuristic). The path's weight is the phase function over pdf(), which for time-angular
/// sampling depends on the next distance, drawn before the direction (AngularQuery::distance).
class AngularMixture {
public:
    AngularMixture(const AngularSampler& strategy, bool mis) : strategy_(strategy), mis_(mis) {}

    struct Sample {
        Vec3 wo;
        double phase = 0;  ///< the phase function's value for wo
        double pdf = 0;    ///< pdf() of wo
    };
    /// A direction from two uniform numbers, plus, with mis, one choosing the component.
    Sample sample(const AngularQuery& q, Sampler& sampler) const {
        const Vec2 u = sampler.next_2d();
        const bool use_phase = mis_ && sampler.next_1d() < 0.5f;
        Sample s;
        s.wo = use_phase ? q.phase->sample(q.wi, u) : strategy_.sample(q, u);
        s.phase = double(q.phase->eval(q.wi, s.wo));
        s.pdf = pdf(q, s.phase, s.wo);
        return s;
    }
    /// Solid-angle density of sample() returning wo, where the phase function's value is
    /// `phase`.
    double pdf(const AngularQuery& q, double phase, const Vec3& wo) const {
        const double a = strategy_.pdf(q, wo);
        return mis_ ? 0.5 * (phase + a) : a;
    }

private:
    const AngularSampler& strategy_;
    bool mis_;
};

/// The DistanceMixture of the medium asked for last, kept: a strategy's rates are fixed for a
/// render, and finding them asks the medium and the strategy through several virtual calls
/// (2-5 % of a path's instructions in fog when done at every segment). Keep one per sample
/// or per path (it holds no lock).
class DistanceMixtureCache {
public:
    DistanceMixtureCache(const DistanceSampler* strategy, bool mis, const DistanceContext& ctx)
        : strategy_(strategy), mis_(mis), ctx_(ctx) {}
    /// Mean-free-path distances alone (no strategy, no time window).
    DistanceMixtureCache() : DistanceMixtureCache(nullptr, false, DistanceContext{kInfinity}) {}
    /// DistanceMixture(medium, strategy, mis, ctx), valid until a call with another medium.
    const DistanceMixture& operator()(const Medium& medium) {
        if (&medium != medium_) {
            mixture_.emplace(medium, strategy_, mis_, ctx_);
            medium_ = &medium;
        }
        return *mixture_;
    }

private:
    const DistanceSampler* strategy_;
    bool mis_;
    DistanceContext ctx_;
    const Medium* medium_ = nullptr;
    std::optional<DistanceMixture> mixture_;
};

/// How likely distance sampling (a DistanceMixture in each medium, restarted at every boundary)
/// is to reach the far end of a segment that crosses media in pieces, walking from either end:
/// what a bidirectional integrator's MIS weights need of a segment that one strategy samples
/// from its start, another from its end, and a third connects without sampling. An end that is
/// a medium vertex is reached with the density (per unit length) of stopping there; an end on
/// a surface with the probability of passing every piece. Vacuum pieces are passed surely.
class SegmentDensities final : public MediumPieces {
public:
    SegmentDensities(const DistanceSampler* strategy, bool mis, const DistanceContext& ctx)
        : mixture(strategy, mis, ctx) {}

    /// The distance strategy in each medium (kept across clear()).
    DistanceMixtureCache mixture;

    /// Forgets the pieces: a new segment.
    void clear() {
        pieces_ = media_ = 0;
        first_ = last_ = Piece{};
        after_first_ = before_last_ = 1.0;
    }
    /// The next piece from the segment's start (MediumPieces; null: vacuum).
    std::optional<Color> piece(const Medium* medium, double length) override {
        if (!medium) {
            add_vacuum();
            return std::nullopt;
        }
        const DistanceMixture& m = mixture(*medium);
        const DistanceMixture::AtDistance at = m.at(length);
        add(at.survival, at.pdf);
        return m.transmittance(at);
    }
    /// A piece in vacuum (passed surely).
    void add_vacuum() { ++pieces_; }
    /// A medium piece with its probability of passing it and density of stopping at its end.
    void add(double survival, double density) {
        ++pieces_;
        if (media_ == 0) {
            first_ = {survival, density};
        } else {
            after_first_ *= survival;
            before_last_ *= last_.survival;
        }
        last_ = {survival, density};
        ++media_;
    }
    /// Density of reaching the end walking from the start.
    double forward(bool end_in_medium) const {
        return media_ == 0 ? 1.0 : before_last_ * (end_in_medium ? last_.density : last_.survival);
    }
    /// Density of reaching the start walking from the end.
    double backward(bool start_in_medium) const {
        return media_ == 0 ? 1.0
                           : after_first_ * (start_in_medium ? first_.density : first_.survival);
    }
    /// Whether the segment lies in one medium, with no boundary on it.
    bool single_medium() const { return pieces_ == 1 && media_ == 1; }

private:
    struct Piece {
        double survival = 1.0, density = 0.0;
    };
    int pieces_ = 0, media_ = 0;  // all pieces; those in a medium
    Piece first_, last_;
    double after_first_ = 1.0, before_last_ = 1.0;  // survival of all pieces but the first / last
};

/// A distance drawn along a ray in a medium: a medium vertex before the surface at `tmax`, or
/// the surface. The weight is transmittance * sigma_s / pdf at a vertex and transmittance /
/// P(passing) at the surface, so the estimate is unbiased for any rate (ratio-tracked
/// transmittance in heterogeneous media).
struct DistanceSample {
    bool scattered = false;  ///< a medium vertex at `distance`; else the path reaches tmax
    double distance = 0.0;
    double pdf = 0.0;  ///< of the vertex, when scattered
    Color weight{1.f, 1.f, 1.f};
    /// The strategy's survival and density at the segment's end (`distance` when scattered, a
    /// finite tmax otherwise; zero when the ray leaves to infinity): what a bidirectional
    /// integrator's segment densities need of it, from the exponential the weight took.
    DistanceMixture::AtDistance at{0.0, 0.0};
};
DistanceSample sample_distance(const Medium& medium, const Ray& ray, double tmax,
                               const DistanceMixture& strategy, double u, Sampler& sampler);

/// How far along a segment (origin o, unit direction d, in a medium of index eta) a vertex can
/// lie and still connect to `target` within `remaining` optical length: the connection covers
/// eta * r in the medium and then at least |x(r) - target| (nothing is faster than light in
/// vacuum). Bounds where a connection strategy samples (eq. 5.110-5.111); wherever its density
/// is zero the distance strategy's vertices keep the whole weight, so nothing is missed.
double connection_reach(const Vec3& o, const Vec3& d, const Vec3& target, double eta,
                        double remaining);

}  // namespace femto
