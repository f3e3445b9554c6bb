// Tangent factorisation with a singularity check on the pivots.
#include "fem/linear_solver.hpp"

#include <sstream>

namespace phymul::fem {

namespace {

// Smallest/largest pivot below which K_ff is taken as singular: a rigid motion left free
// gives round-off pivots (~1e-16 of the largest), while nu = 0.499 on fine meshes stays
// above 1e-6.
constexpr double kSingularPivotRatio = 1e-13;

std::string singular_message(double ratio) {
  std::ostringstream out;
  out.precision(3);
  out << "the tangent stiffness is singular (smallest/largest pivot " << ratio
      << "): the prescribed displacements leave a rigid-body motion free";
  return out.str();
}

}  // namespace

TangentSolver::TangentSolver(const SparseMatrix& lower, const NodeGeometry& geometry) {
  cholesky_.analyze(lower, &geometry);
}

bool TangentSolver::factorize(const SparseMatrix& lower, FactorFailure& failure) {
  if (!cholesky_.factorize(lower)) return factorize_indefinite(lower, failure);
  indefinite_ = false;
  if (cholesky_.pivot_ratio() < kSingularPivotRatio) {
    failure = {singular_message(cholesky_.pivot_ratio()), true};
    return false;
  }
  return true;
}

bool TangentSolver::factorize_indefinite(const SparseMatrix& lower, FactorFailure& failure) {
  if (!ldlt_) {
    ldlt_ = std::make_unique<Ldlt>();
    ldlt_->analyzePattern(lower);
  }
  indefinite_ = true;
  ldlt_->factorize(lower);
  if (ldlt_->info() != Eigen::Success) {
    failure = {"the LDL^T factorisation of the indefinite tangent failed", false};
    return false;
  }
  const Eigen::VectorXd d = ldlt_->vectorD().cwiseAbs();
  const double ratio = d.minCoeff() / d.maxCoeff();
  if (!(ratio >= kSingularPivotRatio)) {
    failure = {singular_message(ratio), true};
    return false;
  }
  return true;
}

Eigen::VectorXd TangentSolver::solve(const Eigen::VectorXd& b) const {
  return indefinite_ ? Eigen::VectorXd(ldlt_->solve(b)) : cholesky_.solve(b);
}

}  // namespace phymul::fem
