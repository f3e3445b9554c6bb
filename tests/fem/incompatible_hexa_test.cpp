// The hexahedron with incompatible modes (HexaElement::incompatible_modes): what Wilson's
// modes are for (pure bending reproduced exactly, where the plain trilinear element is far
// too stiff), the patch test on distorted elements (Taylor's det J0 / det J scaling), and
// rigid motions. Its tangent is checked with the others in element_test.cpp.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "fem/system.hpp"
#include "phymul/fem.hpp"
#include "phymul/mesh.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

constexpr double kYoung = 1e5;  // Pa

double largest_error(const fem::Result& r, const Mesh& mesh, auto&& exact) {
  double e = 0.0;
  for (std::size_t n = 0; n < mesh.points.size(); ++n)
    e = std::max(e, (r.displacement[n] - exact(mesh.points[n])).norm());
  return e;
}

// Pure bending of a 100 x 10 x 20 mm beam, nu = 0, small strain: u_x = -x z / R,
// u_z = x^2 / (2 R), u_y = 0, a field quadratic in x that the modes 1 - xi^2 contain. Both end
// faces are given the exact displacements, the rest is solved for: the interior nodes must
// land on the exact field, and the end face must carry the beam-theory moment E I / R (exact
// here: sigma_xx = -E z / R is the whole stress). The trilinear element with mean dilatation
// cannot bend without shearing (shear locking): its end moment comes out too large, which
// is what makes this test able to fail.
TEST(IncompatibleHexa, PureBendingIsExactWhereTheTrilinearElementLocks) {
  const double length = 0.1, width = 0.01, height = 0.02, curvature = 0.2;  // 1/R in 1/m
  const Mesh mesh =
      make_box({length, width, height}, {5, 1, 2}, CellType::hexa, Vec3(length / 2, 0.0, 0.0));
  const auto exact = [&](const Vec3& p) {
    return Vec3(-p.x() * p.z() * curvature, 0.0, 0.5 * p.x() * p.x() * curvature);
  };
  const double moment = kYoung * width * height * height * height / 12.0 * curvature;
  const double tip = 0.5 * length * length * curvature;
  for (const fem::HexaElement hexa :
       {fem::HexaElement::incompatible_modes, fem::HexaElement::mean_dilatation}) {
    fem::Problem p;
    p.mesh = mesh;
    p.material = {fem::Law::linear, kYoung, 0.0, hexa};
    p.load_steps = 1;
    std::vector<int> end;
    for (std::size_t n = 0; n < mesh.points.size(); ++n) {
      const Vec3& x = mesh.points[n];
      if (std::abs(x.x() - length) < 1e-12) end.push_back(int(n));
      if (std::abs(x.x()) > 1e-12 && std::abs(x.x() - length) > 1e-12) continue;
      for (int axis = 0; axis < 3; ++axis) p.prescribed.push_back({int(n), axis, exact(x)[axis]});
    }
    const fem::Result r = fem::solve_static(p);
    ASSERT_TRUE(r.converged) << r.message;
    double end_moment = 0.0;  // about the y axis through the section's centre
    for (int n : end) end_moment += mesh.points[n].z() * r.reaction[n].x();
    if (hexa == fem::HexaElement::incompatible_modes) {
      EXPECT_LT(largest_error(r, mesh, exact), 1e-10 * tip);
      EXPECT_NEAR(std::abs(end_moment), moment, 1e-9 * moment);
    } else {
      EXPECT_GT(std::abs(end_moment), 1.1 * moment);  // measured: 1.41 times
    }
  }
}

// A block of distorted hexahedra (interior nodes moved at random) under a homogeneous
// finite deformation imposed on its boundary: every node must follow it, for the
// Neo-Hookean law at nu = 0.45. Without the det J0 / det J scaling the modes would not
// integrate to zero on these elements and would pull the interior off the homogeneous field.
TEST(IncompatibleHexa, PassesThePatchTestOnDistortedElements) {
  Mesh mesh = make_box(Vec3::Constant(0.03), {3, 3, 3}, CellType::hexa);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.003, 0.003);
  std::vector<char> boundary(mesh.points.size(), 0);
  for (const auto& [name, nodes] : mesh.node_sets)
    for (int n : nodes) boundary[n] = 1;
  for (std::size_t n = 0; n < mesh.points.size(); ++n)
    if (!boundary[n]) mesh.points[n] += testing::random_vec3(jitter, rng);

  Eigen::Matrix3d grad;  // F - I: stretch, shear and a turn
  grad << 0.08, 0.05, -0.02, -0.03, -0.06, 0.04, 0.01, 0.02, 0.1;
  const auto exact = [&](const Vec3& x) -> Vec3 { return grad * x; };
  fem::Problem p;
  p.mesh = mesh;
  p.material = {fem::Law::neo_hookean, kYoung, 0.45, fem::HexaElement::incompatible_modes};
  p.load_steps = 2;
  for (std::size_t n = 0; n < mesh.points.size(); ++n)
    if (boundary[n])
      for (int axis = 0; axis < 3; ++axis)
        p.prescribed.push_back({int(n), axis, exact(mesh.points[n])[axis]});
  const fem::Result r = fem::solve_static(p);
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_LT(largest_error(r, mesh, exact), 1e-10 * 0.03);
}

TEST(IncompatibleHexa, NoForceAtRestOrUnderARigidMotion) {
  const Mesh mesh = make_box(Vec3(0.03, 0.02, 0.04), {3, 2, 2}, CellType::hexa);
  fem::System s(mesh, {fem::Law::neo_hookean, kYoung, 0.499, fem::HexaElement::incompatible_modes},
                std::vector<char>(3 * mesh.points.size(), 0));
  ASSERT_TRUE(s.evaluate(Eigen::VectorXd::Zero(s.dof_count()), true));
  EXPECT_EQ(s.internal_force().lpNorm<Eigen::Infinity>(), 0.0);

  Eigen::VectorXd stretch = Eigen::VectorXd::Zero(s.dof_count());
  for (std::size_t n = 0; n < mesh.points.size(); ++n) stretch[3 * n] = 0.01 * mesh.points[n].x();
  ASSERT_TRUE(s.evaluate(stretch, false));
  const double force_scale = s.internal_force().lpNorm<Eigen::Infinity>();

  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(2.0, Vec3(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
  Eigen::VectorXd rigid(s.dof_count());
  for (std::size_t n = 0; n < mesh.points.size(); ++n)
    rigid.segment<3>(3 * Eigen::Index(n)) =
        turn * mesh.points[n] + Vec3(0.3, -0.1, 0.05) - mesh.points[n];
  ASSERT_TRUE(s.evaluate(rigid, true));
  EXPECT_LT(s.internal_force().lpNorm<Eigen::Infinity>(), 1e-9 * force_scale);
}

}  // namespace
}  // namespace phymul
