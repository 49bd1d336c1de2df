// femto public API: time-sampling strategies for participating media (thesis ch. 5.6), nested
// in an integrator: <distance> (how far a path travels before its next medium vertex).
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
    static double mean_free_path_rate(const Medium& medium) {
        if (!medium.homogeneous()) return double(medium.majorant());
        const Color st = medium.sigma_t(Vec3(0.f));
        return (double(st.r) + double(st.g) + double(st.b)) / 3.0;
    }

    /// Samples a distance from one uniform u in [0, 1): -ln(1 - u) / lambda.
    static double sample(double lambda, double u) { return -std::log1p(-u) / lambda; }
    /// Density of a sampled distance r.
    static double pdf(double lambda, double r) { return lambda * std::exp(-lambda * r); }
    /// Probability that the sampled distance exceeds d (the path reaches the next surface).
    static double survival(double lambda, double d) { return std::exp(-lambda * d); }
};

}  // namespace femto
