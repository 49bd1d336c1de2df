// Internal linear algebra of the BTF PCA (femto/btf_prefilter.h).
#pragma once

#include <cstddef>
#include <vector>

namespace femto::btf {

/// Symmetric eigen-decomposition of an n x n matrix (row-major, Jacobi rotations): eigenvalues
/// in decreasing order, eigenvectors as the columns of `vectors`.
void symmetric_eigen(std::vector<double> a, size_t n, std::vector<double>& values,
                     std::vector<double>& vectors);

}  // namespace femto::btf
