#include <gtest/gtest.h>

#include <random>

#include "constraints/constraints.hpp"
#include "support/kernels.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

Model balloon(std::vector<int> fixed = {}) {
  Model model;
  const int c =
      add_elastic_component(model, "balloon", make_ellipsoid_surface({0.03, 0.02, 0.025}, 3),
                            testing::surface_material(20.0, 0.05, FrameMode::polar));
  add_volume_constraint(model, c);
  if (!fixed.empty()) add_fixed_nodes(model, fixed);
  finalize(model);
  return model;
}

TEST(VolumeConstraint, ProjectionHitsTheTargetUnderRandomDeformations) {
  const Model model = balloon({0, 5, 17, 40});
  const VolumeConstraint& c = model.volumes.at(0);
  std::mt19937 rng(5);
  std::normal_distribution<double> jitter(0.0, 0.003);
  std::vector<Vec3> grad(size_t(model.node_count()));
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Vec3> x = model.rest_position;
    for (Vec3& p : x) p += testing::random_vec3(jitter, rng);
    for (int i : {0, 5, 17, 40}) x[i] = model.rest_position[i];
    // A squeeze along z loses about a quarter of the volume before the projection.
    for (Vec3& p : x) p.z() *= 0.75;
    for (int i : {0, 5, 17, 40}) x[i] = model.rest_position[i];
    const std::vector<Vec3> before = x;
    project_volume(c, model.inverse_mass, x, grad);
    const double V = enclosed_volume(x, c.triangles);
    EXPECT_LT(std::abs(V - c.target_volume) / c.target_volume, 1e-10) << trial;
    for (int i : {0, 5, 17, 40}) {
      EXPECT_EQ(x[i].x(), before[i].x());  // bit for bit
      EXPECT_EQ(x[i].y(), before[i].y());
      EXPECT_EQ(x[i].z(), before[i].z());
    }
  }
}

TEST(VolumeConstraint, HeldAxesAreNotMoved) {
  Model model = balloon();
  // Hold every node's z: the projection may only move nodes in x and y.
  add_prescribed_displacement(
      model,
      {model.volumes[0].nodes, {false, false, true}, Schedule::constant(Vec3(0, 0, -0.004))});
  finalize(model);
  std::vector<Vec3> x = model.rest_position;
  std::vector<Vec3> grad(x.size());
  Data data = allocate_data(model);
  apply_position_constraints(model, data.controls, *data.work, x, 0.0, grad);
  for (int i = 0; i < model.node_count(); ++i)
    EXPECT_EQ(x[i].z(), model.rest_position[i].z() - 0.004);
  // A pure translation keeps the volume: the constraint must leave it as it is.
  const double V = enclosed_volume(x, model.volumes[0].triangles);
  EXPECT_LT(std::abs(V / model.volumes[0].target_volume - 1.0), 1e-12);
}

TEST(VolumeConstraint, GradientMatchesFiniteDifferences) {
  const Model model = balloon();
  const VolumeConstraint& c = model.volumes[0];
  std::vector<Vec3> grad(size_t(model.node_count()));
  std::vector<Vec3> x = model.rest_position;
  volume_gradient(c, x, grad);
  // V is linear in each single coordinate, so a wide central difference is exact and
  // keeps round-off small.
  const double h = 1e-3;
  for (int i : {1, 9, 33})
    for (int a = 0; a < 3; ++a) {
      std::vector<Vec3> p = x, m = x;
      p[i][a] += h;
      m[i][a] -= h;
      const double fd =
          (enclosed_volume(p, c.triangles) - enclosed_volume(m, c.triangles)) / (2 * h);
      EXPECT_NEAR(grad[i][a], fd, 1e-12 * std::abs(fd) + 1e-17);
    }
}

TEST(VolumeConstraint, OpenSurfaceIsRefused) {
  Mesh open = make_ellipsoid_surface({0.03, 0.02, 0.025}, 1);
  open.cells.pop_back();
  Model model;
  const int c = add_elastic_component(model, "sheet", open,
                                      testing::surface_material(20.0, 0.05, FrameMode::polar));
  try {
    add_volume_constraint(model, c);
    FAIL() << "an open surface was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("closed surface"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace phymul
