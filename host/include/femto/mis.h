// femto public API: multiple importance sampling weights (Veach 1997, ch. 9).
//
// Each heuristic weighs a sample drawn by technique A (density a) against technique B
// (density b) that could have drawn it too; the weights of all techniques sum to 1 for every
// sample, so the combined estimator stays unbiased.
#pragma once

namespace femto {

/// Power heuristic (exponent 2) for one sample of each technique: a^2 / (a^2 + b^2).
inline float power_heuristic(float a, float b) {
    const float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0 ? a2 / (a2 + b2) : 0.f;
}

/// Power heuristic for n_a samples of density a against n_b samples of density b.
inline float power_heuristic(float n_a, float a, float n_b, float b) {
    return power_heuristic(n_a * a, n_b * b);
}

/// Balance heuristic a / (a + b): the weight of a one-sample mixture of two techniques, and
/// what the time-sampling strategies use against their steady counterparts (ch. 5.6).
inline double balance_heuristic(double a, double b) { return a + b > 0 ? a / (a + b) : 0.0; }

}  // namespace femto
