// The implicit step's triangular solves with its kept factor (solver/implicit_step.cpp,
// implicit_contacts.cpp).
#pragma once

#include "model/implicit_system.hpp"

namespace phymul {

// X = P^-1 X for k right-hand sides at once, X row-major in the permuted order (row p's k
// values at x + p k): one pass over the factor for all of them, the k values of a row
// contiguous (an axis's residual and each volume's gradient, for each axis sharing the
// factor), where k separate solves would read the factor k times.
// K: the count at compile time (unrolled), or 0 for any count k.
template <int K>
void solve_block(const ImplicitFactor& f, double* __restrict x, int count) {
  const int k = K > 0 ? K : count;
  const Eigen::SparseMatrix<double>& L = f.llt.matrixL().nestedExpression();
  const int n = int(L.cols());
  const int* __restrict start = L.outerIndexPtr();
  const int* __restrict row = L.innerIndexPtr();
  const double* __restrict value = L.valuePtr();
  for (int j = 0; j < n; ++j) {  // L Y = X; each column's diagonal comes first
    double* __restrict xj = x + size_t(j) * size_t(k);
    const double inverse = 1.0 / value[start[j]];
    for (int c = 0; c < k; ++c) xj[c] *= inverse;
    for (int e = start[j] + 1; e < start[j + 1]; ++e) {
      double* __restrict xi = x + size_t(row[e]) * size_t(k);
      const double l = value[e];
      for (int c = 0; c < k; ++c) xi[c] -= l * xj[c];
    }
  }
  for (int j = n - 1; j >= 0; --j) {  // L^T X = Y
    double* __restrict xj = x + size_t(j) * size_t(k);
    for (int e = start[j] + 1; e < start[j + 1]; ++e) {
      const double* __restrict xi = x + size_t(row[e]) * size_t(k);
      const double l = value[e];
      for (int c = 0; c < k; ++c) xj[c] -= l * xi[c];
    }
    const double inverse = 1.0 / value[start[j]];
    for (int c = 0; c < k; ++c) xj[c] *= inverse;
  }
}

}  // namespace phymul
