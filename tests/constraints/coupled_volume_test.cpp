// Several volume constraints at once: closed surfaces sharing nodes, and targets that follow
// a schedule (bladder filling).
#include <gtest/gtest.h>

#include "constraints/constraints.hpp"
#include "phymul/simulation.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

// An 8 x 4 x 4 cm block whose two halves (x < 0, x > 0) each keep their own volume: the two
// closed surfaces share the 25 nodes of the wall x = 0.
Model two_chambers(const Schedule& left_target = {}) {
  const Mesh mesh = make_box(Vec3(0.08, 0.04, 0.04), {8, 4, 4}, CellType::hexa);
  Model model;
  const int c = add_elastic_component(model, "block", mesh, testing::material(20.0));
  model.volumes.push_back(
      testing::surface_of_cells(mesh, "left", [](const Vec3& p) { return p.x() < 0; }));
  model.volumes.push_back(
      testing::surface_of_cells(mesh, "right", [](const Vec3& p) { return p.x() > 0; }));
  model.volumes[0].target_schedule = left_target;
  add_fixed_nodes(model, model.components[c].node_sets.at("bottom"));
  // A plate pushed 1 cm down on the top, and gravity: both chambers are squeezed.
  add_prescribed_displacement(model, {model.components[c].node_sets.at("top"),
                                      {false, false, true},
                                      Schedule{{0.0, 0.2}, {Vec3::Zero(), Vec3(0, 0, -0.01)}}});
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 5.0;
  finalize(model);
  return model;
}

double relative_error(const Model& m, const Data& s, int k) {
  const VolumeConstraint& c = m.volumes[size_t(k)];
  const double target = c.target_at(s.time);
  return std::abs(enclosed_volume(s.x, c.triangles) - target) / target;
}

TEST(CoupledVolumes, TwoChambersSharingAWallKeepBothVolumesEveryStep) {
  const Model model = two_chambers();
  ASSERT_TRUE(model.coupled_volumes);
  for (Integrator scheme : {Integrator::verlet, Integrator::newton_cotes}) {
    Model m = model;
    m.settings.integrator = scheme;
    Simulator sim(m);
    double worst = 0.0;
    double wall_moved = 0.0;
    while (sim.data().time < 0.3) {
      sim.step();
      worst = std::max({worst, relative_error(m, sim.data(), 0), relative_error(m, sim.data(), 1)});
    }
    for (int i = 0; i < m.node_count(); ++i)
      if (m.rest_position[i].x() == 0.0)
        wall_moved = std::max(wall_moved, (sim.data().x[i] - m.rest_position[i]).norm());
    std::printf("two chambers (%s): worst relative volume error %.3g, wall moved %.3g m\n",
                scheme == Integrator::verlet ? "verlet" : "newton-cotes", worst, wall_moved);
    EXPECT_LT(worst, 1e-10);
    EXPECT_GT(wall_moved, 1e-3);  // the squeeze really deforms the shared wall
  }
}

// The joint projection multiplies two surfaces' gradients only where both are non-zero: the
// 5 x 5 nodes of the wall, each listed once with its place in both constraints.
TEST(CoupledVolumes, TheSharedWallIsIndexedForTheProductsOfTwoGradients) {
  const Model model = two_chambers();
  const VolumeConstraint &left = model.volumes[0], &right = model.volumes[1];
  EXPECT_TRUE(left.shared.empty());
  ASSERT_EQ(right.shared.size(), 25u);
  int previous = -1;
  for (const auto& [l, here, there] : right.shared) {
    EXPECT_EQ(l, 0);
    const int node = right.nodes[size_t(here)];
    EXPECT_EQ(left.nodes[size_t(there)], node);
    EXPECT_EQ(model.rest_position[size_t(node)].x(), 0.0);
    EXPECT_GT(node, previous);  // by node: the order of the sums over the nodes
    previous = node;
  }
}

TEST(CoupledVolumes, VelocitiesAreTangentToBothConstraints) {
  Simulator sim(two_chambers());
  const Model& m = sim.model();
  std::vector<Vec3> grad(size_t(m.node_count()));
  for (int k = 0; k < 200; ++k) sim.step();
  for (const VolumeConstraint& c : m.volumes) {
    volume_gradient(c, sim.data().x, grad);
    double rate = 0.0, scale = 0.0;
    for (int i : c.nodes) {
      rate += grad[i].dot(sim.data().v[i]);
      scale += grad[i].norm() * sim.data().v[i].norm();
    }
    std::printf("%s: dV/dt %.3g m^3/s against a scale of %.3g\n", c.component.c_str(), rate, scale);
    EXPECT_GT(scale, 0.0);
    EXPECT_LT(std::abs(rate), 1e-11 * scale);
  }
}

TEST(CoupledVolumes, ScheduledTargetIsFollowedWhileTheOtherChamberKeepsItsVolume) {
  // The left chamber fills by 20 % in 0.2 s and then holds; the right one must not change.
  const double v0 = 0.04 * 0.04 * 0.04;
  const Model m = two_chambers(Schedule{{0.0, 0.2}, {Vec3(v0, 0, 0), Vec3(1.2 * v0, 0, 0)}});
  Simulator sim(m);
  double worst = 0.0;
  while (sim.data().time < 0.3) {
    sim.step();
    worst = std::max({worst, relative_error(m, sim.data(), 0), relative_error(m, sim.data(), 1)});
  }
  const double left = enclosed_volume(sim.data().x, m.volumes[0].triangles);
  std::printf("filling: worst relative error %.3g, left chamber %.6g m^3 (target %.6g)\n", worst,
              left, 1.2 * v0);
  EXPECT_LT(worst, 1e-10);
  EXPECT_NEAR(left, 1.2 * v0, 1e-10 * v0);
}

TEST(CoupledVolumes, StaticRelaxationConvergesWithSharedNodes) {
  // The residual takes out what the two coupled pressures balance together; relaxation then
  // reaches a tight tolerance and both volumes stay exact.
  Model m = two_chambers();
  m.settings.tolerance = 1e-9;
  Simulator sim(m);
  const StaticResult r = sim.relax(0.2, 50000);
  std::printf("two chambers static: %s in %ld iterations, residual %.3g N\n",
              r.converged ? "converged" : "NOT converged", r.iterations, r.residual);
  EXPECT_TRUE(r.converged);
  EXPECT_LT(relative_error(m, sim.data(), 0), 1e-10);
  EXPECT_LT(relative_error(m, sim.data(), 1), 1e-10);
  // The supports carry the weight: the pressures of the two chambers cancel out overall.
  Vec3 support = Vec3::Zero();
  for (const Vec3& f : sim.support_reactions()) support += f;
  double weight = 0.0;
  for (double mass : m.mass) weight += mass * 9.81;
  EXPECT_NEAR(support.z(), weight, m.node_count() * m.settings.tolerance);
  EXPECT_NEAR(support.x(), 0.0, m.node_count() * m.settings.tolerance);
}

TEST(CoupledVolumes, BalloonFollowsAFillingSchedule) {
  Model model;
  const int c =
      add_elastic_component(model, "bladder", make_ellipsoid_surface({0.03, 0.03, 0.03}, 3),
                            testing::surface_material(5.0, 0.05, FrameMode::polar));
  add_volume_constraint(model, c);
  const double v0 = model.volumes[0].target_volume;
  model.volumes[0].target_schedule = Schedule{{0.0, 0.5}, {Vec3(v0, 0, 0), Vec3(3 * v0, 0, 0)}};
  add_fixed_nodes(model, {0});
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 10.0;
  finalize(model);
  EXPECT_FALSE(model.coupled_volumes);
  Simulator sim(model);
  double worst = 0.0;
  while (sim.data().time < 0.6) {
    sim.step();
    worst = std::max(worst, relative_error(model, sim.data(), 0));
  }
  EXPECT_LT(worst, 1e-10);
  EXPECT_NEAR(enclosed_volume(sim.data().x, model.volumes[0].triangles), 3 * v0, 1e-10 * v0);
}

}  // namespace
}  // namespace phymul
