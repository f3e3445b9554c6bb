// Bad input is rejected with std::invalid_argument naming the field, the range and the value;
// problems that only show while solving (a free rigid motion, an impossible load) come back
// as converged = false with a message.
#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

#include "fem/fem_test_util.hpp"

namespace phymul {
namespace {

using fem_test::contains;

fem::Problem small_problem() {
  return fem_test::bonded_compression(1, 0.05, 0.45, CellType::hexa, 1);
}

std::string rejection(const std::function<void(fem::Problem&)>& spoil) {
  fem::Problem p = small_problem();
  spoil(p);
  try {
    (void)fem::solve_static(p);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(FemInput, MaterialOutOfRange) {
  const std::string nu_half = rejection([](fem::Problem& p) { p.material.poisson = 0.5; });
  EXPECT_TRUE(contains(nu_half, "material.poisson must be in (-1, 0.5) (got 0.5)"));
  EXPECT_TRUE(contains(rejection([](fem::Problem& p) { p.material.poisson = -1.0; }),
                       "material.poisson must be in (-1, 0.5) (got -1)"));
  EXPECT_TRUE(contains(rejection([](fem::Problem& p) {
                         p.material.poisson = std::numeric_limits<double>::quiet_NaN();
                       }),
                       "material.poisson"));
  EXPECT_TRUE(contains(rejection([](fem::Problem& p) { p.material.young = 0.0; }),
                       "material.young must be finite and > 0 Pa (got 0)"));
  EXPECT_TRUE(contains(rejection([](fem::Problem& p) { p.material.young = -3.5; }), "(got -3.5)"));
}

TEST(FemInput, UnsupportedCellAndNodeOutOfRange) {
  const std::string wedge = rejection([](fem::Problem& p) {
    p.mesh = make_cylinder_volume(0.01, 0.02, 6, 1, 1);
    p.prescribed.clear();
  });
  EXPECT_TRUE(contains(wedge, "mesh.cells[0] is a wedge; only linear hexa and tetra"));
  const std::string node = rejection([](fem::Problem& p) { p.mesh.cells[0].nodes[5] = 8; });
  EXPECT_TRUE(contains(node, "mesh.cells[0].nodes[5] must be in [0, 8) (got 8)"));
  const std::string negative = rejection([](fem::Problem& p) { p.mesh.cells[0].nodes[0] = -1; });
  EXPECT_TRUE(contains(negative, "mesh.cells[0].nodes[0] must be in [0, 8) (got -1)"));
  const std::string inverted = rejection(
      [](fem::Problem& p) { std::swap(p.mesh.cells[0].nodes[0], p.mesh.cells[0].nodes[4]); });
  EXPECT_TRUE(contains(inverted, "invalid mesh"));
  EXPECT_TRUE(
      contains(rejection([](fem::Problem& p) { p.mesh.cells.clear(); }), "mesh.cells is empty"));
}

TEST(FemInput, PrescribedAndControls) {
  EXPECT_TRUE(contains(rejection([](fem::Problem& p) { p.prescribed[0].node = 99; }),
                       "prescribed[0].node must be in [0, 8) (got 99)"));
  EXPECT_TRUE(contains(rejection([](fem::Problem& p) { p.prescribed[1].axis = 3; }),
                       "prescribed[1].axis must be 0, 1 or 2 (got 3)"));
  EXPECT_TRUE(contains(rejection([](fem::Problem& p) {
                         p.prescribed.push_back(p.prescribed[0]);
                         p.prescribed.back().value = 1e-3;
                       }),
                       "but an earlier entry set it to 0 m"));
  EXPECT_TRUE(contains(rejection([](fem::Problem& p) { p.load_steps = 0; }),
                       "load_steps must be >= 1 (got 0)"));
  EXPECT_TRUE(contains(rejection([](fem::Problem& p) { p.max_newton_iterations = 0; }),
                       "max_newton_iterations must be >= 1 (got 0)"));
  EXPECT_TRUE(contains(rejection([](fem::Problem& p) { p.tolerance = 0.0; }),
                       "tolerance must be in (0, 1) (got 0)"));
  EXPECT_TRUE(contains(rejection([](fem::Problem& p) {
                         p.body_force.x() = std::numeric_limits<double>::infinity();
                       }),
                       "body_force must be finite"));
  // The same value twice is not a conflict.
  EXPECT_EQ(rejection([](fem::Problem& p) { p.prescribed.push_back(p.prescribed[0]); }), "");
}

TEST(FemSolve, FreeRigidMotionIsReportedNotSolved) {
  fem::Problem p = small_problem();
  p.prescribed.clear();
  p.body_force = Vec3(0, 0, -10.0);
  const fem::Result r = fem::solve_static(p);
  EXPECT_FALSE(r.converged);
  EXPECT_TRUE(contains(r.message, "rigid-body motion free"));
}

// 110 % compression cannot be reached: the increment is bisected, the solve goes as far as
// it can and says where it stopped; the displacement returned is that last equilibrium.
TEST(FemSolve, ImpossibleLoadFailsWithTheLoadFactorReached) {
  fem::Problem p = fem_test::bonded_compression(2, 1.1, 0.45, CellType::hexa, 1);
  p.max_newton_iterations = 8;
  const fem::Result r = fem::solve_static(p);
  EXPECT_FALSE(r.converged);
  EXPECT_TRUE(contains(r.message, "load step 1 of 1 did not converge (equilibrium reached at"));
  EXPECT_TRUE(contains(r.message, "bisected 8 times"));
  const double top = r.displacement[p.mesh.node_sets["top"][0]].z();
  EXPECT_LT(top, -0.3 * fem_test::kCubeSize);  // got a good way
  EXPECT_GT(top, -1.1 * fem_test::kCubeSize);
  EXPECT_LT(r.final_residual, 1e-6);  // the state returned is an equilibrium
}

// A single load step to 18.25 % converges (the line search and, if needed, bisection take
// care of it) to the same equilibrium as ten steps.
TEST(FemSolve, OneLoadStepReachesTheSameEquilibriumAsTen) {
  fem::Problem one = fem_test::bonded_compression(4, 0.1825, 0.499, CellType::hexa, 1);
  fem::Problem ten = fem_test::bonded_compression(4, 0.1825, 0.499, CellType::hexa, 10);
  const fem::Result a = fem::solve_static(one);
  const fem::Result b = fem::solve_static(ten);
  ASSERT_TRUE(a.converged) << a.message;
  ASSERT_TRUE(b.converged) << b.message;
  const double fa = fem_test::set_reaction(a, one.mesh.node_sets["top"], 2);
  const double fb = fem_test::set_reaction(b, ten.mesh.node_sets["top"], 2);
  EXPECT_NEAR(fa, fb, 1e-8 * std::abs(fb));
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

TEST(FemInput, PerCellMaterialsAndNodalForcesAreChecked) {
  using fem_test::contains;
  const auto reject = [](const std::function<void(fem::Problem&)>& spoil) {
    fem::Problem p = fem_test::bonded_compression(1, 0.05, 0.45, CellType::hexa, 1);
    spoil(p);
    try {
      (void)fem::solve_static(p);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_TRUE(contains(reject([](fem::Problem& p) {
                         p.materials = {p.material, p.material};
                       }),
                       "cell_material must have one entry per cell (1; got 0)"));
  EXPECT_TRUE(contains(reject([](fem::Problem& p) {
                         p.materials = {p.material};
                         p.cell_material = {1};
                       }),
                       "cell_material[0] must be in [0, 1) (got 1)"));
  EXPECT_TRUE(contains(reject([](fem::Problem& p) {
                         p.materials = {p.material};
                         p.materials[0].poisson = 0.7;
                         p.cell_material = {0};
                       }),
                       "material.poisson must be in (-1, 0.5) (got 0.7)"));
  EXPECT_TRUE(contains(reject([](fem::Problem& p) { p.nodal_force.assign(3, Vec3::Zero()); }),
                       "nodal_force must be empty or have one entry per node (8; got 3)"));
  EXPECT_TRUE(contains(reject([](fem::Problem& p) {
                         p.nodal_force.assign(8, Vec3::Zero());
                         p.nodal_force[2].x() = std::numeric_limits<double>::infinity();
                       }),
                       "nodal_force[2] must be finite"));
  EXPECT_TRUE(contains(reject([](fem::Problem& p) { p.force_tolerance = 0.0; }),
                       "force_tolerance must be > 0 N (got 0)"));
}

}  // namespace
}  // namespace phymul
