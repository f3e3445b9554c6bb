// The supernodal Cholesky against dense factorisations, for both orderings, on mesh
// stiffness matrices and on random sparse matrices (forests, single columns, diagonals).
#include "fem/sparse_cholesky.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <numeric>
#include <random>

#include "fem/fem_test_util.hpp"
#include "fem/linear_solver.hpp"
#include "fem/system.hpp"

namespace phymul {
namespace {

// Lower triangle of a dense matrix: its non-zeros and the whole diagonal.
fem::SparseMatrix lower_of(const Eigen::MatrixXd& dense) {
  std::vector<Eigen::Triplet<double, int>> entries;
  for (int j = 0; j < dense.cols(); ++j) {
    for (int i = j; i < dense.rows(); ++i) {
      if (i == j || dense(i, j) != 0.0) entries.emplace_back(i, j, dense(i, j));
    }
  }
  fem::SparseMatrix m(dense.rows(), dense.cols());
  m.setFromTriplets(entries.begin(), entries.end());
  m.makeCompressed();
  return m;
}

// Random symmetric matrix with `per_column` off-diagonal entries per column, made positive
// definite by diagonal dominance or indefinite by a negative diagonal entry.
Eigen::MatrixXd random_symmetric(int n, int per_column, bool definite, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < n; ++j) {
    for (int k = 0; k < per_column; ++k) {
      const int i = pick(rng);
      if (i == j) continue;
      a(i, j) = a(j, i) = value(rng);
    }
  }
  for (int j = 0; j < n; ++j) a(j, j) = a.col(j).cwiseAbs().sum() + 1.0;
  if (!definite) a(n / 2, n / 2) = -a(n / 2, n / 2);
  return a;
}

// Relative error of the sparse solve against the dense LLT one.
double solve_error(const fem::SparseMatrix& lower, const fem::NodeGeometry* geometry) {
  fem::SupernodalCholesky c;
  c.analyze(lower, geometry);
  EXPECT_TRUE(c.factorize(lower));
  const Eigen::MatrixXd dense = Eigen::MatrixXd(lower).selfadjointView<Eigen::Lower>();
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(lower.rows(), -1.0, 2.0);
  const Eigen::VectorXd expected = dense.llt().solve(b);
  return (c.solve(b) - expected).norm() / expected.norm();
}

TEST(FemSparseCholesky, RandomMatricesWithMinimumDegreeOrder) {
  for (int n : {1, 2, 7, 60, 300}) {
    for (int per_column : {0, 1, 3}) {
      const fem::SparseMatrix m = lower_of(random_symmetric(n, per_column, true, unsigned(n)));
      EXPECT_LT(solve_error(m, nullptr), 1e-12) << "n " << n << " per column " << per_column;
    }
  }
}

// The tangent of the bonded 4^3 cube at its 10 % equilibrium, nu = 0.499, with nested
// dissection and minimum degree; factorised twice to check the reuse of the analysis.
TEST(FemSparseCholesky, MeshTangentWithBothOrders) {
  fem::Problem p = fem_test::bonded_compression(4, 0.1, 0.499, CellType::hexa, 2);
  const fem::Result r = fem::solve_static(p);
  ASSERT_TRUE(r.converged) << r.message;
  std::vector<char> mask(3 * p.mesh.points.size(), 0);
  for (const fem::Dirichlet& d : p.prescribed) mask[3 * d.node + d.axis] = 1;
  fem::System s(p.mesh, p.material, mask);
  Eigen::VectorXd u(s.dof_count());
  for (std::size_t n = 0; n < p.mesh.points.size(); ++n) {
    u.segment<3>(3 * Eigen::Index(n)) = r.displacement[n];
  }
  ASSERT_TRUE(s.evaluate(u, true));
  fem::NodeGeometry geometry{{}, p.mesh.points};
  for (int dof : s.free_dofs()) geometry.group.push_back(dof / 3);
  EXPECT_LT(solve_error(s.free_free(), &geometry), 1e-9);
  EXPECT_LT(solve_error(s.free_free(), nullptr), 1e-9);

  fem::SupernodalCholesky c;
  c.analyze(s.free_free(), &geometry);
  ASSERT_TRUE(c.factorize(s.free_free()));
  ASSERT_TRUE(s.evaluate(0.5 * u, true));  // same pattern, new values
  ASSERT_TRUE(c.factorize(s.free_free()));
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(s.free_count());
  const Eigen::MatrixXd k = Eigen::MatrixXd(s.free_free()).selfadjointView<Eigen::Lower>();
  EXPECT_LT((k * c.solve(b) - b).norm(), 1e-9 * b.norm());
  EXPECT_GT(c.pivot_ratio(), 1e-8);
}

// Nested dissection of a structured grid numbers the middle plane of nodes last.
TEST(FemSparseCholesky, NestedDissectionEndsWithTheMiddlePlane) {
  const Mesh mesh = make_box(Vec3(0.04, 0.02, 0.02), {8, 4, 4}, CellType::hexa);
  fem::System s(mesh, {}, std::vector<char>(3 * mesh.points.size(), 0));
  fem::NodeGeometry geometry{{}, mesh.points};
  for (int dof : s.free_dofs()) geometry.group.push_back(dof / 3);
  const std::vector<int> order = fem::nested_dissection(s.free_free(), geometry);
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  std::vector<int> all(s.free_count());
  std::iota(all.begin(), all.end(), 0);
  EXPECT_EQ(sorted, all);
  const int plane = 5 * 5 * 3;  // nodes of the plane x = 0, three unknowns each
  for (int k = s.free_count() - plane; k < s.free_count(); ++k) {
    EXPECT_NEAR(mesh.points[order[k] / 3].x(), 0.0, 1e-12);
  }
}

// An indefinite matrix is refused by the Cholesky factorisation and solved by the LDL^T
// fallback of the tangent solver.
TEST(FemSparseCholesky, IndefiniteMatrixFallsBackToLdlt) {
  const Eigen::MatrixXd dense = random_symmetric(50, 2, false, 11);
  const fem::SparseMatrix m = lower_of(dense);
  fem::SupernodalCholesky c;
  c.analyze(m);
  EXPECT_FALSE(c.factorize(m));

  fem::NodeGeometry geometry;
  for (int i = 0; i < 50; ++i) {
    geometry.group.push_back(i);
    geometry.position.push_back(Vec3(i, 0, 0));
  }
  fem::TangentSolver solver(m, geometry);
  fem::FactorFailure failure;
  ASSERT_TRUE(solver.factorize(m, failure)) << failure.reason;
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(50);
  EXPECT_LT((dense * solver.solve(b) - b).norm(), 1e-12 * b.norm());
}

}  // namespace
}  // namespace phymul
