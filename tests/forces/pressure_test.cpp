#include "forces/pressure.hpp"

#include <gtest/gtest.h>

#include <random>

#include "phymul/forces.hpp"
#include "support/kernels.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

// 4 x 4 x 2 cm box, 5 mm hexa cells, centred at the origin.
Model box_model() {
  Model model;
  add_elastic_component(model, "block", make_box(Vec3(0.04, 0.04, 0.02), {8, 8, 4}, CellType::hexa),
                        testing::material(30.0));
  finalize(model);
  return model;
}

std::vector<Triangle> faces_with_all_nodes_at_z(const Model& model, double z) {
  std::vector<Triangle> faces;
  for (const Triangle& t : model.components[0].boundary)
    if (model.rest_position[t[0]].z() == z && model.rest_position[t[1]].z() == z &&
        model.rest_position[t[2]].z() == z)
      faces.push_back(t);
  return faces;
}

Vec3 resultant(const std::vector<Vec3>& f) {
  Vec3 sum = Vec3::Zero();
  for (const Vec3& fi : f) sum += fi;
  return sum;
}

Vec3 torque(const std::vector<Vec3>& x, const std::vector<Vec3>& f) {
  Vec3 sum = Vec3::Zero();
  for (size_t i = 0; i < x.size(); ++i) sum += x[i].cross(f[i]);
  return sum;
}

std::vector<Vec3> pressure_forces(const PressureLoad& load, const std::vector<Vec3>& x) {
  std::vector<Vec3> f(x.size(), Vec3::Zero());
  add_pressure_forces(load, x, f, 0.0);
  return f;
}

TEST(Pressure, FlatPatchCarriesPressureTimesAreaAlongMinusNormal) {
  const Model model = box_model();
  const double p = 2500.0;
  const PressureLoad load{0, faces_with_all_nodes_at_z(model, 0.01), Schedule::constant({p, 0, 0})};
  ASSERT_EQ(load.faces.size(), 8u * 8u * 2u);
  const Vec3 total = resultant(pressure_forces(load, model.rest_position));
  const double expected = p * 0.04 * 0.04;  // 4 N
  EXPECT_NEAR(total.z(), -expected, 1e-12 * expected);
  EXPECT_NEAR(total.x(), 0.0, 1e-12 * expected);
  EXPECT_NEAR(total.y(), 0.0, 1e-12 * expected);
}

TEST(Pressure, ClosedSurfaceHasNoResultantAndNoTorque) {
  Model model;
  add_elastic_component(model, "ellipsoid",
                        make_ellipsoid_volume({0.03, 0.02, 0.025}, 3, 2, Vec3(0.01, -0.02, 0.005)),
                        testing::material(30.0));
  finalize(model);
  const double p = 1000.0;
  const PressureLoad load{0, model.components[0].boundary, Schedule::constant({p, 0, 0})};
  // A deformed state: the sums vanish for any closed polyhedron, not only at rest.
  std::vector<Vec3> x = model.rest_position;
  std::mt19937 rng(3);
  std::normal_distribution<double> jitter(0.0, 0.002);
  for (Vec3& q : x) q += testing::random_vec3(jitter, rng);
  double area = 0.0;
  for (const Triangle& t : load.faces)
    area += 0.5 * (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).norm();
  const std::vector<Vec3> f = pressure_forces(load, x);
  const double scale = p * area;
  EXPECT_LT(resultant(f).norm(), 1e-12 * scale);
  // The lumped forces put each face's p*A at its centroid: the torque of a closed surface
  // vanishes exactly too. Lever arms about 0.05 m.
  EXPECT_LT(torque(x, f).norm(), 1e-12 * scale * 0.05);
}

TEST(Pressure, CylinderSelectsTheFacesAlongItsAxis) {
  const Model model = box_model();
  // Axis along x on the top face (z = 1 cm): the 2 mm radius catches, in every quad along
  // y = 0, the one triangle whose centroid is 5/3 mm from the cell edge (centroids of the
  // other triangles lie 10/3 mm away, those of the side faces 2.4 mm).
  const std::vector<Triangle> faces =
      faces_in_cylinder(model, 0, Vec3(0, 0, 0.01), Vec3(1, 0, 0), 0.002);
  ASSERT_EQ(faces.size(), 16u);
  for (const Triangle& t : faces) {
    double y = 0.0;
    for (int i : t) {
      EXPECT_EQ(model.rest_position[i].z(), 0.01);
      y += model.rest_position[i].y() / 3.0;
    }
    EXPECT_NEAR(std::abs(y), 0.005 / 3.0, 1e-15);
  }
  EXPECT_THROW(faces_in_cylinder(model, 1, Vec3::Zero(), Vec3::UnitZ(), 0.01),
               std::invalid_argument);
}

TEST(Pressure, FollowsTheBodyWhenItRotates) {
  const Model model = box_model();
  const PressureLoad load{0, faces_with_all_nodes_at_z(model, 0.01),
                          Schedule::constant({2500.0, 0, 0})};
  std::mt19937 rng(7);
  const Eigen::Matrix3d R = testing::random_rotation(rng);
  std::vector<Vec3> x = model.rest_position;
  for (Vec3& q : x) q = R * q + Vec3(0.1, 0.2, -0.3);
  const Vec3 at_rest = resultant(pressure_forces(load, model.rest_position));
  const Vec3 rotated = resultant(pressure_forces(load, x));
  EXPECT_LT((rotated - R * at_rest).norm(), 1e-12 * at_rest.norm());
}

TEST(Pressure, ComputeForcesAddsThePressureAtTheLoadTime) {
  Model model = box_model();
  const std::vector<Triangle> top = faces_with_all_nodes_at_z(model, 0.01);
  add_pressure(model, {0, top, Schedule{{0.0, 1.0}, {Vec3::Zero(), Vec3(1000.0, 0, 0)}}});
  EXPECT_THROW(add_pressure(model, {3, top, Schedule::constant(Vec3::Zero())}),
               std::invalid_argument);
  Data s = allocate_data(model);
  compute_forces(model, s, 0.5);
  // At rest the shape memory is balanced: what is left is half the final pressure.
  EXPECT_NEAR(resultant(s.f).z(), -500.0 * 0.04 * 0.04, 1e-9);
}

}  // namespace
}  // namespace phymul
