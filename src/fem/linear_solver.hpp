// Factorisation of the free-free tangent K_ff: the supernodal Cholesky (nested dissection
// order) while K_ff is positive definite, Eigen's SimplicialLDLT when it is not (past a limit
// point the tangent may be indefinite; LDL^T without pivoting still factors it in practice).
#pragma once

#include <Eigen/SparseCholesky>
#include <memory>
#include <string>

#include "fem/sparse_cholesky.hpp"

namespace phymul::fem {

struct FactorFailure {
  std::string reason;
  bool fatal = false;  // singular: no smaller load increment can help
};

class TangentSolver {
 public:
  // Symbolic analysis of the pattern of `lower` (lower triangle of K_ff).
  TangentSolver(const SparseMatrix& lower, const NodeGeometry& geometry);

  bool factorize(const SparseMatrix& lower, FactorFailure& failure);
  Eigen::VectorXd solve(const Eigen::VectorXd& b) const;

 private:
  using Ldlt = Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower>;
  bool factorize_indefinite(const SparseMatrix& lower, FactorFailure& failure);

  SupernodalCholesky cholesky_;
  std::unique_ptr<Ldlt> ldlt_;  // analysed on first need
  bool indefinite_ = false;     // the last factorisation is the LDL^T one
};

}  // namespace phymul::fem
