// femto public API: time-sampling strategies for participating media (thesis ch. 5.6), nested
// in an integrator: <distance> (how far a path travels before its next medium vertex),
// <connection> (where on a ray segment an extra vertex connects to a light) and <angular>
// (which direction a path leaves a medium vertex in). Each strategy is sample + pdf, so any
// integrator (path tracing today, bidirectional methods later) can call it and weigh it
// against its steady counterpart by multiple importance sampling.
//
// A distance strategy samples the exponential p(r) = lambda e^(-lambda r) along a ray in a
// medium; strategies differ in the rate lambda. Mean-free-path sampling uses the medium's
// extinction (steady state: vertices crowd where light is bright, i.e. early). The
// `exponential` strategy picks lambda from the film's time window so that vertex *times* are
// uniform (eq. 5.21-5.23, appendix 5.C.1): the sum over vertices of the densities of their
// times is the constant (lambda / eta) for any exponential, so lambda sets how many vertices
// a path has on average before the window ends. Integrators call sample()/pdf(), or mix two
// strategies by multiple importance sampling with the mixture helpers below.
#pragma once

#include <cmath>

#include "femto/math.h"
#include "femto/medium.h"
#include "femto/object.h"

namespace femto {

/// What a distance strategy may look at.
struct DistanceContext {
    double window_end = 0;  ///< latest optical path length the film records (scene units)
};

class DistanceSampler : public Object {
public:
    PluginKind kind() const override { return PluginKind::Distance; }

    /// Rate lambda (per scene unit of length) of the exponential used in `medium`; 0 means
    /// the path never interacts there.
    virtual double rate(const Medium& medium, const DistanceContext& ctx) const = 0;
    /// Called once before rendering; throws a SceneError when the strategy cannot work with
    /// this context (e.g. a rate derived from a time window the film does not have).
    virtual void prepare(const DistanceContext& /*ctx*/) const {}

    /// The steady (mean-free-path) rate in `medium`: the mean of sigma_t's channels when it
    /// is homogeneous, the majorant otherwise (the path weight then carries the ratio-tracked
    /// transmittance).
    static double mean_free_path_rate(const Medium& medium) { return mean_free_path(medium).rate; }
    /// The same rate, and whether it is the extinction of a homogeneous medium that is the same
    /// in every channel (its survival exp(-rate d) is then the medium's transmittance).
    struct MeanFreePath {
        double rate;
        bool grey_homogeneous;
    };
    static MeanFreePath mean_free_path(const Medium& medium) {
        if (!medium.homogeneous()) return {double(medium.majorant()), false};
        const Color st = medium.sigma_t(Vec3(0.f));
        return {(double(st.r) + double(st.g) + double(st.b)) / 3.0, st.r == st.g && st.r == st.b};
    }

    /// Samples a distance from one uniform u in [0, 1): -ln(1 - u) / lambda.
    static double sample(double lambda, double u) { return -std::log1p(-u) / lambda; }
    /// Density of a sampled distance r.
    static double pdf(double lambda, double r) { return lambda * std::exp(-lambda * r); }
    /// Probability that the sampled distance exceeds d (the path reaches the next surface).
    static double survival(double lambda, double d) { return std::exp(-lambda * d); }
};

/// A ray segment in a medium on which a connection strategy places a vertex, and the point
/// (usually on a light) that vertex will connect to (ch. 5.6.2, Fig. 5.6 middle).
struct ConnectionQuery {
    Vec3 origin;        ///< where the segment starts (the previous path vertex)
    Vec3 direction;     ///< unit direction of the segment
    double length = 0;  ///< the vertex must lie in [0, length); may be +infinity
    Vec3 target;        ///< the point the new vertex connects to
};

class ConnectionSampler : public Object {
public:
    PluginKind kind() const override { return PluginKind::Connection; }

    /// False for `deterministic`: no extra vertex; the integrator casts its ordinary shadow
    /// rays from the vertices the distance strategy places.
    virtual bool places_vertex() const { return true; }
    /// A distance along the segment in [0, q.length) from one uniform u in [0, 1), or a
    /// negative value when the segment holds no vertex worth placing.
    virtual double sample(const ConnectionQuery& q, double u) const = 0;
    /// Density (per unit length) of sample() returning r.
    virtual double pdf(const ConnectionQuery& q, double r) const = 0;
};

/// The segment of a connection query seen from its target: l = target - origin, b = l .
/// direction (where the target projects on the line), d2 = |l|^2 - b^2 its squared distance
/// from the line (in double: with the target nearly on the line it must not be lost against
/// r^2 and |l|^2), and D that distance kept a hair above zero.
struct ConnectionGeometry {
    double l2, b, d2, D;
    explicit ConnectionGeometry(const ConnectionQuery& q);
    /// |x(r) - target| for x(r) = origin + r direction, as sqrt((r - b)^2 + d2).
    double distance_to_target(double r) const { return std::sqrt((r - b) * (r - b) + d2); }
};

/// Equiangular sampling (Kulla & Fajardo 2012): a distance on the query's segment with density
/// proportional to 1 / |x(r) - target|^2, the falloff of a point light's irradiance. The
/// steady reference of the connection strategies; works for an infinite segment too. Returns
/// a negative value when the segment is too short to resolve.
double equiangular_sample(const ConnectionQuery& q, double u);
/// Density (per unit length) of equiangular_sample() returning r.
double equiangular_pdf(const ConnectionQuery& q, double r);

/// A medium vertex choosing its outgoing direction (ch. 5.6.3, Fig. 5.6 right).
struct AngularQuery {
    Vec3 position;                         ///< the vertex
    Vec3 wi;                               ///< unit direction back along the incoming path
    const PhaseFunction* phase = nullptr;  ///< the medium's phase function
    /// Distance to the next vertex, drawn by the distance strategy before the direction
    /// (infinite when the path will not scatter again in this medium).
    double distance = kInfinity;
    bool has_target = false;  ///< false when no finite target exists (no light)
    Vec3 target;              ///< the point the path aims to reach (a light)
};

class AngularSampler : public Object {
public:
    PluginKind kind() const override { return PluginKind::Angular; }

    /// True for `phase` (steady state): nothing to combine by MIS.
    virtual bool steady() const { return false; }
    /// A unit direction from two uniforms.
    virtual Vec3 sample(const AngularQuery& q, Vec2 u) const = 0;
    /// Solid-angle density of sample() returning wo.
    virtual double pdf(const AngularQuery& q, const Vec3& wo) const = 0;
};

}  // namespace femto
