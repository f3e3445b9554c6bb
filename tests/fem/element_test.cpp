// Element level: shape functions, rest and rigid-motion invariance, and the tangent against
// finite differences of the assembled residual (which is itself checked against the energy).
#include "fem/element.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "fem/fem_test_util.hpp"
#include "fem/system.hpp"

namespace phymul {
namespace {

using fem_test::kCubeYoung;

Eigen::VectorXd random_displacement(int size, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::VectorXd u(size);
  for (int i = 0; i < size; ++i) u[i] = amplitude * uniform(rng);
  return u;
}

// A system with every dof free, so K_ff is the full tangent.
fem::System free_system(const Mesh& mesh, fem::Law law, double poisson,
                        fem::HexaElement hexa = fem::HexaElement::mean_dilatation) {
  return fem::System(mesh, {law, kCubeYoung, poisson, hexa},
                     std::vector<char>(3 * mesh.points.size(), 0));
}

Eigen::MatrixXd dense_tangent(const fem::System& s) {
  return Eigen::MatrixXd(s.free_free()).selfadjointView<Eigen::Lower>();
}

// Displacement of the rigid motion x -> R X + t.
Eigen::VectorXd rigid_displacement(const Mesh& mesh, const Eigen::Matrix3d& r, const Vec3& t) {
  Eigen::VectorXd u(3 * mesh.points.size());
  for (std::size_t n = 0; n < mesh.points.size(); ++n) {
    u.segment<3>(3 * Eigen::Index(n)) = r * mesh.points[n] + t - mesh.points[n];
  }
  return u;
}

TEST(FemHexa, ShapeFunctionsPartitionUnityAndReproduceLinearFields) {
  // A sheared, stretched parallelepiped: the trilinear map is affine, so the gradients of
  // a linear field are exact and the volume is the box product.
  Eigen::Matrix3d a;
  a << 0.02, 0.003, -0.001, 0.0, 0.015, 0.002, 0.001, 0.0, 0.01;
  const std::array<Vec3, 8> unit{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0),
                                 Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(1, 1, 1), Vec3(0, 1, 1)};
  Eigen::Matrix<double, 3, 8> x;
  for (int i = 0; i < 8; ++i) x.col(i) = a * unit[i] + Vec3(0.1, -0.2, 0.3);
  const fem::HexaReference ref = fem::hexa_reference(x, 0);
  EXPECT_NEAR(ref.volume, a.determinant(), 1e-15 * std::abs(a.determinant()) + 1e-20);
  EXPECT_NEAR(ref.nodal_volume.sum(), ref.volume, 1e-12 * ref.volume);

  Eigen::Matrix3d g;  // gradient of the linear field v(X) = G X
  g << 1, 2, 3, -4, 5, 6, 7, -8, 9;
  const Eigen::Matrix<double, 3, 8> v = g * x;
  for (int p = 0; p < 8; ++p) {
    EXPECT_LT(ref.grad[p].colwise().sum().norm(), 1e-9);  // sum_a grad N_a = 0
    EXPECT_LT((v * ref.grad[p] - g).norm(), 1e-10 * g.norm());
  }
}

TEST(FemTetra, GradientsAndVolume) {
  Eigen::Matrix<double, 3, 4> x;
  x << 0, 0.01, 0, 0, 0, 0, 0.02, 0, 0, 0, 0, 0.03;
  const fem::TetraReference ref = fem::tetra_reference(x, 0);
  EXPECT_NEAR(ref.volume, 0.01 * 0.02 * 0.03 / 6.0, 1e-20);
  Eigen::Matrix3d g;
  g << 1, 2, 3, -4, 5, 6, 7, -8, 9;
  EXPECT_LT((g * x * ref.grad[0] - g).norm(), 1e-12 * g.norm());
}

TEST(FemElement, InvertedElementIsRejectedNotEvaluated) {
  Mesh mesh = make_box(Vec3::Constant(0.01), {1, 1, 1}, CellType::hexa);
  fem::System s = free_system(mesh, fem::Law::neo_hookean, 0.45);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(s.dof_count());
  for (int n : mesh.node_sets["top"]) u[3 * n + 2] = -0.015;  // top below the bottom
  EXPECT_FALSE(s.evaluate(u, true));
}

// At rest every law gives exactly zero force and energy; under a large rigid motion the
// Neo-Hookean law is frame invariant, so the force is round-off compared with the force of a
// 1 % strain. (The linear law is not: it is only valid for small rotations.)
class FemRigidMotion : public ::testing::TestWithParam<CellType> {};

TEST_P(FemRigidMotion, ZeroResidualAtRestAndUnderRotationPlusTranslation) {
  const Mesh mesh = make_box(Vec3(0.03, 0.02, 0.04), {3, 2, 2}, GetParam(), Vec3(0.01, 0, 0));
  fem::System s = free_system(mesh, fem::Law::neo_hookean, 0.499);
  ASSERT_TRUE(s.evaluate(Eigen::VectorXd::Zero(s.dof_count()), true));
  EXPECT_EQ(s.internal_force().lpNorm<Eigen::Infinity>(), 0.0);
  EXPECT_EQ(s.energy(), 0.0);

  Eigen::VectorXd stretch = Eigen::VectorXd::Zero(s.dof_count());
  for (std::size_t n = 0; n < mesh.points.size(); ++n) stretch[3 * n] = 0.01 * mesh.points[n].x();
  ASSERT_TRUE(s.evaluate(stretch, false));
  const double force_scale = s.internal_force().lpNorm<Eigen::Infinity>();

  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(2.0, Vec3(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
  ASSERT_TRUE(s.evaluate(rigid_displacement(mesh, r, Vec3(0.3, -0.1, 0.05)), true));
  EXPECT_LT(s.internal_force().lpNorm<Eigen::Infinity>(), 1e-9 * force_scale);
  EXPECT_LT(std::abs(s.energy()), 1e-12 * kCubeYoung * 0.03 * 0.02 * 0.04);
}

INSTANTIATE_TEST_SUITE_P(Cells, FemRigidMotion, ::testing::Values(CellType::hexa, CellType::tetra));

struct TangentCase {
  CellType type;
  fem::Law law;
  double poisson;
  fem::HexaElement hexa = fem::HexaElement::mean_dilatation;
};

class FemTangent : public ::testing::TestWithParam<TangentCase> {};

// K is the exact Hessian of the energy, hence equal to the central finite difference of the
// internal force up to O(h^2) and round-off: ~1e-11 relative here, required 1e-6. The force
// is in turn the finite-difference gradient of the energy. The deformation is random with
// displacements of 10 % of the cell size (strains ~ 20 %, rotations included).
TEST_P(FemTangent, MatchesCentralFiniteDifferences) {
  const TangentCase c = GetParam();
  const Mesh mesh = make_box(Vec3::Constant(0.02), {2, 2, 2}, c.type);
  fem::System s = free_system(mesh, c.law, c.poisson, c.hexa);
  const Eigen::VectorXd u = random_displacement(s.dof_count(), 0.001, 7);
  ASSERT_TRUE(s.evaluate(u, true));
  const Eigen::MatrixXd k = dense_tangent(s);
  const Eigen::VectorXd force = s.internal_force();

  const double h = 1e-8;  // m: 1e-5 of the displacement scale
  Eigen::MatrixXd k_fd(k.rows(), k.cols());
  Eigen::VectorXd force_fd(force.size());
  for (int j = 0; j < s.dof_count(); ++j) {
    Eigen::VectorXd plus = u, minus = u;
    plus[j] += h;
    minus[j] -= h;
    ASSERT_TRUE(s.evaluate(plus, false));
    const Eigen::VectorXd f_plus = s.internal_force();
    const double e_plus = s.energy();
    ASSERT_TRUE(s.evaluate(minus, false));
    k_fd.col(j) = (f_plus - s.internal_force()) / (2 * h);
    force_fd[j] = (e_plus - s.energy()) / (2 * h);
  }
  EXPECT_LT((k - k_fd).norm(), 1e-6 * k.norm());
  EXPECT_LT((k - k.transpose()).norm(), 1e-14 * k.norm());
  EXPECT_LT((force - force_fd).norm(), 1e-6 * force.norm());
}

INSTANTIATE_TEST_SUITE_P(
    Laws, FemTangent,
    ::testing::Values(TangentCase{CellType::hexa, fem::Law::neo_hookean, 0.499},
                      TangentCase{CellType::hexa, fem::Law::neo_hookean, 0.3},
                      TangentCase{CellType::hexa, fem::Law::neo_hookean, -0.5},
                      TangentCase{CellType::tetra, fem::Law::neo_hookean, 0.3},
                      TangentCase{CellType::tetra, fem::Law::neo_hookean, 0.499},
                      TangentCase{CellType::hexa, fem::Law::linear, 0.499},
                      TangentCase{CellType::tetra, fem::Law::linear, 0.3},
                      TangentCase{CellType::hexa, fem::Law::neo_hookean, 0.499,
                                  fem::HexaElement::incompatible_modes},
                      TangentCase{CellType::hexa, fem::Law::neo_hookean, 0.3,
                                  fem::HexaElement::incompatible_modes},
                      TangentCase{CellType::hexa, fem::Law::linear, 0.45,
                                  fem::HexaElement::incompatible_modes}));

// The linear law is the linearisation of the Neo-Hookean one at rest: for a 1e-6 strain
// their forces agree to O(strain), i.e. ~1e-6 relative.
TEST(FemLaws, LinearIsTheSmallStrainLimitOfNeoHookean) {
  const Mesh mesh = make_box(Vec3::Constant(0.02), {2, 2, 2}, CellType::hexa);
  fem::System nh = free_system(mesh, fem::Law::neo_hookean, 0.45);
  fem::System lin = free_system(mesh, fem::Law::linear, 0.45);
  const Eigen::VectorXd u = random_displacement(nh.dof_count(), 1e-8, 3);
  ASSERT_TRUE(nh.evaluate(u, true));
  ASSERT_TRUE(lin.evaluate(u, true));
  EXPECT_LT((nh.internal_force() - lin.internal_force()).norm(),
            1e-5 * lin.internal_force().norm());
  EXPECT_LT((dense_tangent(nh) - dense_tangent(lin)).norm(), 1e-5 * dense_tangent(lin).norm());
  EXPECT_NEAR(nh.energy(), lin.energy(), 1e-5 * lin.energy());
}

// Mean dilatation: the bending (hourglass-like) mode u_x = c x y of a centred hexa has
// tr(grad u) = c y, non-zero at every Gauss point but zero on average. With the element-mean
// dilatation it costs shear energy only, proportional to mu, so nu = 0.499999 and nu = 0
// give energies in the ratio of their shear moduli; with pointwise J the first would carry
// a kappa term ~1e5 times larger (the locking that mean dilatation removes).
TEST(FemElement, BendingModeWithZeroMeanDilatationCostsNoVolumetricEnergy) {
  const Mesh mesh = make_box(Vec3::Constant(0.01), {1, 1, 1}, CellType::hexa);
  fem::System stiff = free_system(mesh, fem::Law::linear, 0.499999);
  fem::System soft = free_system(mesh, fem::Law::linear, 0.0);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(stiff.dof_count());
  for (std::size_t n = 0; n < mesh.points.size(); ++n) {
    u[3 * Eigen::Index(n)] = 0.1 * mesh.points[n].x() * mesh.points[n].y();
  }
  ASSERT_TRUE(stiff.evaluate(u, false));
  ASSERT_TRUE(soft.evaluate(u, false));
  const double mu_ratio = (1.0 + 0.0) / (1.0 + 0.499999);
  EXPECT_GT(soft.energy(), 0.0);
  EXPECT_NEAR(stiff.energy(), mu_ratio * soft.energy(), 1e-12 * soft.energy());
}

}  // namespace
}  // namespace phymul
