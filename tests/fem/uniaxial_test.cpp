// Homogeneous states the discrete solution must reproduce exactly: uniaxial stress with
// rollers (linear law against E A strain, Neo-Hookean against the analytic 1-D solution),
// a rigid motion, and global equilibrium under a body force.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "fem/fem_test_util.hpp"

namespace phymul {
namespace {

using fem_test::set_reaction;

constexpr double kSize = 0.01;  // m

// Nominal (first Piola-Kirchhoff) stress P_33 of the law W = mu/2 (J^-2/3 I1 - 3) +
// kappa/2 (J - 1)^2 for F = diag(a, a, stretch), with a the lateral stretch that makes
// P_11 = 0, found by Newton's method on P_11(a) with a numerical derivative. Written from
// the formulas, independently of the element code.
double uniaxial_neo_hookean_stress(double stretch, double mu, double kappa) {
  const auto p_ii = [&](double a, double own) {  // P of the direction with stretch `own`
    const double j = a * a * stretch;
    const double i1 = 2 * a * a + stretch * stretch;
    return mu * std::pow(j, -2.0 / 3.0) * (own - i1 / (3 * own)) + kappa * (j - 1) * j / own;
  };
  double a = 1.0 / std::sqrt(stretch);  // incompressible guess
  for (int it = 0; it < 100; ++it) {
    const double f = p_ii(a, a);
    const double h = 1e-7 * a;
    const double step = f / ((p_ii(a + h, a + h) - p_ii(a - h, a - h)) / (2 * h));
    a -= step;
    if (std::abs(step) < 1e-15 * a) break;
  }
  EXPECT_LT(std::abs(p_ii(a, a)), 1e-9 * std::abs(p_ii(a, stretch)));
  return p_ii(a, stretch);
}

struct RollerCase {
  CellType type;
  int cells;
};

class FemUniaxialLinear : public ::testing::TestWithParam<RollerCase> {};

// Small-strain uniaxial stress: sigma_zz = E strain, lateral strain -nu strain, exact for the
// element (the state is linear in X), so the top reaction equals E A strain to round-off.
TEST_P(FemUniaxialLinear, ReactionIsEAStrainAndLateralStrainIsMinusNuStrain) {
  const double strain = 1e-3;
  const fem::Material material{fem::Law::linear, 14.9e3, 0.3};
  fem::Problem p =
      fem_test::uniaxial_rollers(kSize, GetParam().cells, strain, material, GetParam().type);
  p.load_steps = 2;
  const fem::Result r = fem::solve_static(p);
  ASSERT_TRUE(r.converged) << r.message;
  const double expected = material.young * kSize * kSize * strain;
  EXPECT_NEAR(set_reaction(r, p.mesh.node_sets["top"], 2), expected, 1e-9 * expected);
  EXPECT_NEAR(set_reaction(r, p.mesh.node_sets["bottom"], 2), -expected, 1e-9 * expected);
  for (std::size_t n = 0; n < p.mesh.points.size(); ++n) {
    const Vec3 expected_u =
        Vec3(-material.poisson * strain * p.mesh.points[n].x(),
             -material.poisson * strain * p.mesh.points[n].y(), strain * p.mesh.points[n].z());
    EXPECT_LT((r.displacement[n] - expected_u).norm(), 1e-12 * kSize) << "node " << n;
  }
  // Linear: the predictor is exact, and one correction confirms it.
  EXPECT_EQ(r.newton_iterations, p.load_steps);
}

INSTANTIATE_TEST_SUITE_P(Meshes, FemUniaxialLinear,
                         ::testing::Values(RollerCase{CellType::hexa, 1},
                                           RollerCase{CellType::hexa, 3},
                                           RollerCase{CellType::tetra, 2}));

struct NeoHookeanCase {
  CellType type;
  int cells;
  double poisson;
};

class FemUniaxialNeoHookean : public ::testing::TestWithParam<NeoHookeanCase> {};

// 20 % compression with rollers: the exact solution is homogeneous (in the element space), so
// the top reaction must equal P_33(0.8) A of the analytic solution; the Newton tolerance
// (1e-10) leaves ~1e-10 relative, the test asks 1e-8.
TEST_P(FemUniaxialNeoHookean, TopReactionMatchesAnalyticHomogeneousSolution) {
  const NeoHookeanCase c = GetParam();
  const fem::Material material{fem::Law::neo_hookean, 14.9e3, c.poisson};
  fem::Problem p = fem_test::uniaxial_rollers(kSize, c.cells, -0.2, material, c.type);
  p.load_steps = 4;
  const fem::Result r = fem::solve_static(p);
  ASSERT_TRUE(r.converged) << r.message;
  const double mu = material.young / (2 * (1 + c.poisson));
  const double kappa = material.young / (3 * (1 - 2 * c.poisson));
  const double expected = uniaxial_neo_hookean_stress(0.8, mu, kappa) * kSize * kSize;
  EXPECT_LT(expected, 0.0);  // compression
  EXPECT_NEAR(set_reaction(r, p.mesh.node_sets["top"], 2), expected, 1e-8 * std::abs(expected));
  // Lateral faces are free: no reaction anywhere but along z on the plates and on the pins.
  EXPECT_LT(r.final_residual, 1e-9 * std::abs(expected));
}

INSTANTIATE_TEST_SUITE_P(Meshes, FemUniaxialNeoHookean,
                         ::testing::Values(NeoHookeanCase{CellType::hexa, 1, 0.499},
                                           NeoHookeanCase{CellType::hexa, 3, 0.3},
                                           NeoHookeanCase{CellType::tetra, 2, 0.3}));

// A rigid motion imposed on the bottom (rotation of 1.5 rad about an oblique axis plus a
// translation) with the rest free: the equilibrium is the same rigid motion everywhere, with
// zero reaction (round-off against the force scale E h^2 ~ 1.5 N of a unit strain).
TEST(FemRigidMotion, PrescribedRigidMotionOfOneFaceMovesTheWholeBlockRigidly) {
  fem::Problem p;
  p.mesh = make_box(Vec3(0.02, 0.02, 0.01), {2, 2, 2}, CellType::hexa);
  p.material = {fem::Law::neo_hookean, 14.9e3, 0.45};
  p.load_steps = 6;
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd(1.5, Vec3(0.3, -1.0, 2.0).normalized()).toRotationMatrix();
  const Vec3 shift(0.005, -0.002, 0.01);
  for (int n : p.mesh.node_sets["bottom"]) {
    const Vec3 u = rot * p.mesh.points[n] + shift - p.mesh.points[n];
    for (int axis = 0; axis < 3; ++axis) p.prescribed.push_back({n, axis, u[axis]});
  }
  const fem::Result r = fem::solve_static(p);
  ASSERT_TRUE(r.converged) << r.message;
  for (std::size_t n = 0; n < p.mesh.points.size(); ++n) {
    const Vec3 expected = rot * p.mesh.points[n] + shift - p.mesh.points[n];
    EXPECT_LT((r.displacement[n] - expected).norm(), 1e-9 * 0.02) << "node " << n;
    EXPECT_LT(r.reaction[n].norm(), 1e-10) << "node " << n;
  }
}

// Body force (dead load): at equilibrium the reactions (the forces the supports exert on the
// body) balance the total load rho g V, to the Newton tolerance, for both laws.
TEST(FemBodyForce, ReactionsBalanceTheTotalBodyForce) {
  for (fem::Law law : {fem::Law::linear, fem::Law::neo_hookean}) {
    fem::Problem p;
    p.mesh = make_box(Vec3(0.02, 0.02, 0.04), {2, 2, 4}, CellType::hexa);
    p.material = {law, 14.9e3, 0.49};
    p.body_force = Vec3(0.0, 0.0, -1000.0 * 9.81);  // water-like density, gravity
    p.load_steps = 2;
    for (int axis = 0; axis < 3; ++axis)
      fem_test::prescribe(p, p.mesh.node_sets["bottom"], axis, 0.0);
    const fem::Result r = fem::solve_static(p);
    ASSERT_TRUE(r.converged) << r.message;
    const double weight = 1000.0 * 9.81 * 0.02 * 0.02 * 0.04;
    Vec3 total = Vec3::Zero();
    for (const Vec3& f : r.reaction) total += f;
    EXPECT_NEAR(total.z(), weight, 1e-9 * weight);
    EXPECT_LT(total.head<2>().norm(), 1e-9 * weight);
    EXPECT_NEAR(set_reaction(r, p.mesh.node_sets["bottom"], 2), weight, 1e-9 * weight);
    // The top sags under its own weight.
    EXPECT_LT(r.displacement[p.mesh.node_sets["top"][0]].z(), 0.0);
  }
}

}  // namespace
}  // namespace phymul
