// The implicit step's coupled matrix (solver/implicit_matrix.hpp) and its block Cholesky
// factor (model/block_cholesky.hpp): the factor solves as a dense solve does, and the matrix
// less its inertia is the shape memory's Hessian at rest, -df/dx of the force pass itself.
#include "solver/implicit_matrix.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <random>

#include "model/block_cholesky.hpp"
#include "phymul/forces.hpp"
#include "phymul/simulation.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

// A random symmetric positive definite matrix of 3x3 blocks on a ring of `blocks` blocks,
// each coupled to the next three (fill-in for the factor), as dense and as lower entries.
Eigen::MatrixXd random_blocks(int blocks, std::vector<BlockEntry>& lower,
                              std::vector<std::pair<int, int>>& pairs) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * blocks, 3 * blocks);
  for (int p = 0; p < blocks; ++p)
    for (int step = 1; step <= 3; ++step) {
      const int q = (p + step * 7) % blocks;
      Block3 b;
      for (int e = 0; e < 9; ++e) b(e / 3, e % 3) = normal(rng);
      dense.block(3 * p, 3 * q, 3, 3) += b;
      dense.block(3 * q, 3 * p, 3, 3) += b.transpose();
      pairs.emplace_back(p, q);
    }
  dense += 20.0 * Eigen::MatrixXd::Identity(3 * blocks, 3 * blocks);  // diagonally dominant
  for (int p = 0; p < blocks; ++p)
    for (int q = 0; q <= p; ++q)
      if (dense.block(3 * p, 3 * q, 3, 3).cwiseAbs().maxCoeff() > 0.0)
        lower.push_back({p, q, dense.block(3 * p, 3 * q, 3, 3)});
  return dense;
}

TEST(BlockCholesky, SolvesAsADenseCholeskyDoes) {
  const int blocks = 60;
  std::vector<BlockEntry> lower;
  std::vector<std::pair<int, int>> pairs;
  const Eigen::MatrixXd dense = random_blocks(blocks, lower, pairs);
  BlockFactor f = analyse_blocks(blocks, pairs, size_t(blocks) * size_t(blocks));
  factorise_blocks(f, lower);
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(3 * blocks, -1.0, 2.0);
  std::vector<double> x(size_t(3 * blocks));
  for (int p = 0; p < blocks; ++p)
    for (int a = 0; a < 3; ++a) x[size_t(3 * f.position[size_t(p)] + a)] = b[3 * p + a];
  solve_blocks(f, x.data());
  const Eigen::VectorXd expected = dense.llt().solve(b);
  double worst = 0.0;
  for (int p = 0; p < blocks; ++p)
    for (int a = 0; a < 3; ++a)
      worst =
          std::max(worst, std::abs(x[size_t(3 * f.position[size_t(p)] + a)] - expected[3 * p + a]));
  EXPECT_LT(worst, 1e-13 * expected.cwiseAbs().maxCoeff());
}

TEST(BlockCholesky, RefusesAMatrixThatIsNotPositiveDefinite) {
  std::vector<std::pair<int, int>> pairs{{1, 0}};
  BlockFactor f = analyse_blocks(2, pairs, 4);
  std::vector<BlockEntry> lower{
      {0, 0, Block3::Identity()}, {1, 1, Block3::Identity()}, {1, 0, 2.0 * Block3::Identity()}};
  EXPECT_THROW(factorise_blocks(f, lower), std::runtime_error);
}

// Central differences of the force pass at rest against the assembled matrix, mass term out.
double largest_mismatch(const Model& model, double& largest) {
  std::array<std::vector<int>, 3> unknown;
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < model.node_count(); ++i)
      unknown[size_t(a)].push_back(model.inverse_mass[size_t(i)][a] > 0.0 ? i : -1);
  const ImplicitBlocks blocks = number_blocks(model, unknown, {});
  const int n = int(blocks.unknown.size());
  const double h = 1.0;
  Eigen::MatrixXd assembled = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (const BlockEntry& e : coupled_matrix(model, blocks, h)) {
    assembled.block(3 * e.row, 3 * e.col, 3, 3) += e.value;
    if (e.row != e.col) assembled.block(3 * e.col, 3 * e.row, 3, 3) += e.value.transpose();
  }
  Data d = make_data(model);
  const double eps = 1e-7;  // m, in the forces' linear range and far above round-off
  Eigen::MatrixXd differenced = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (int i = 0; i < model.node_count(); ++i)
    for (int a = 0; a < 3; ++a) {
      const int b = blocks.of_node[size_t(i)];
      if (b < 0 || blocks.unknown[size_t(b)][size_t(a)] < 0) continue;
      std::array<std::vector<Vec3>, 2> f;
      for (int side = 0; side < 2; ++side) {
        d.x = model.rest_position;
        d.x[size_t(i)][a] += side == 0 ? eps : -eps;
        compute_forces(model, d, 0.0);
        f[size_t(side)] = d.f;
      }
      for (int j = 0; j < model.node_count(); ++j)
        if (const int c = blocks.of_node[size_t(j)]; c >= 0)
          for (int r = 0; r < 3; ++r)
            if (blocks.unknown[size_t(c)][size_t(r)] >= 0)
              differenced(3 * c + r, 3 * b + a) -=
                  (f[0][size_t(j)][r] - f[1][size_t(j)][r]) / (2 * eps);
    }
  for (int i = 0; i < model.node_count(); ++i) {
    const int b = blocks.of_node[size_t(i)];
    for (int a = 0; a < 3 && b >= 0; ++a) {
      double& diagonal = differenced(3 * b + a, 3 * b + a);
      if (blocks.unknown[size_t(b)][size_t(a)] < 0)
        diagonal = 1.0;  // a held axis: the identity's row
      else
        diagonal += model.inertia[size_t(i)] * (1.0 / (h * h) + model.damping / h);
    }
  }
  largest = differenced.cwiseAbs().maxCoeff();
  return (assembled - differenced).cwiseAbs().maxCoeff();
}

// A jittered box of hexahedra (every node fits its rotation; flat faces take the normal pair
// of a volume) and an ellipsoid's surface (rings and their normals), each held on one side.
TEST(ImplicitMatrix, IsTheShapeMemorysHessianAtRest) {
  Model box;
  add_elastic_component(
      box, "box",
      testing::jittered(make_box(Vec3(0.02, 0.02, 0.02), {3, 3, 3}, CellType::hexa), 0.02 / 3),
      testing::material(40.0));
  add_fixed_nodes(box, box.components[0].node_sets.at("top"));
  finalize(box);
  Model surface;
  add_elastic_component(surface, "ball", make_ellipsoid_surface(Vec3(0.03, 0.025, 0.02), 2),
                        testing::surface_material(60.0, 0.05, FrameMode::polar));
  add_fixed_nodes(surface, {0});
  finalize(surface);
  for (const Model* model : {&box, &surface}) {
    double largest = 0.0;
    const double mismatch = largest_mismatch(*model, largest);
    EXPECT_GT(largest, 1.0);  // N/m: the memories' stiffness, not only the inertia
    EXPECT_LT(mismatch, 1e-6 * largest);
    std::printf("%d nodes: largest entry %.3g N/m, mismatch %.3g\n", model->node_count(), largest,
                mismatch);
  }
}

// Explicit finite elements (TLED: one-point hexahedra with their hourglass stiffness, and the
// tetrahedra an ellipsoid's wedges are cut into), nearly incompressible, each held on one
// side: P less the inertia is -df/dx of their force pass at rest.
TEST(ImplicitMatrix, IsTheFiniteElementsHessianAtRest) {
  MaterialSpec fem;
  fem.model = ElasticModel::fem;
  fem.young = 20e3;
  fem.poisson = 0.45;
  fem.density = 1000.0;
  Model box;
  add_elastic_component(
      box, "box",
      testing::jittered(make_box(Vec3(0.02, 0.02, 0.02), {3, 3, 3}, CellType::hexa), 0.02 / 3),
      fem);
  add_fixed_nodes(box, box.components[0].node_sets.at("top"));
  finalize(box);
  Model ball;
  add_elastic_component(ball, "ball", make_ellipsoid_volume(Vec3(0.02, 0.015, 0.015), 2, 3), fem);
  add_fixed_nodes(ball, {0});
  finalize(ball);
  for (const Model* model : {&box, &ball}) {
    ASSERT_FALSE(model->explicit_fem.empty());
    double largest = 0.0;
    const double mismatch = largest_mismatch(*model, largest);
    EXPECT_GT(largest, 100.0);  // N/m: E h for h of millimetres, not the inertia
    EXPECT_LT(mismatch, 1e-6 * largest);
    std::printf("%d nodes, %d cells of %d nodes: largest entry %.3g N/m, mismatch %.3g\n",
                model->node_count(), int(model->explicit_fem[0].volume.size()),
                model->explicit_fem[0].nodes_per_cell, largest, mismatch);
  }
}

}  // namespace
}  // namespace phymul
