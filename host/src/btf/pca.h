// PCA compression of a BTF (Jarabo, Plenoptic Light Transport, ch. 3.9: 99 % of the energy with
// 28.5 % / 8 % of the coefficients at filter scales 2 / 4): per colour channel, the best rank-k
// approximation of the (lights x views) x texels matrix of decoded values, by a randomized SVD
// (Halko, Martinsson and Tropp 2011: a range finder with power iterations, then the exact SVD
// of the small projected matrix). The result is the factorized form the prefiltered hierarchy
// (btf/prefilter.h) works on, so BDIs and log-encoded files get one too.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "btf/prefilter.h"
#include "femto/btf.h"

namespace femto::btf {

struct PcaReport {
    std::array<std::vector<double>, 3> singular_values;  ///< per channel, the k kept
    std::array<double, 3> energy_kept{};     ///< sum of kept sigma^2 / squared Frobenius norm
    std::array<double, 3> relative_error{};  ///< ||M - M_k||_F / ||M||_F, measured
};

struct PcaSettings {
    uint32_t components = 16;
    uint32_t oversampling = 8;  ///< extra random directions of the range finder
    uint32_t power_iterations = 2;
    uint64_t seed = 1;
};

/// The rank-k factors of `data`'s decoded values (components clamped to the matrix's smaller
/// side), with what they keep.
Factors factorize(const Data& data, const PcaSettings& settings, PcaReport* report = nullptr);

/// Symmetric eigen-decomposition of an n x n matrix (row-major, Jacobi rotations): eigenvalues
/// in decreasing order, eigenvectors as the columns of `vectors`.
void symmetric_eigen(std::vector<double> a, size_t n, std::vector<double>& values,
                     std::vector<double>& vectors);

}  // namespace femto::btf
