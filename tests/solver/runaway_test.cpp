// The runaway guard: an unstable run is stopped in the step where neighbouring nodes start
// moving apart by a sizeable part of an element, with finite numbers, before the old criteria
// (non-finite values, a move of 10 model sizes) see anything; rigid motion never trips it.
#include <gtest/gtest.h>

#include <cmath>

#include "phymul/simulation.hpp"
#include "solver/runaway_guard.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

Model jelly(Integrator integrator, double dt_over_stable) {
  Model model;
  const int c = add_elastic_component(model, "jelly",
                                      make_box(Vec3(0.02, 0.02, 0.02), {4, 4, 4}, CellType::hexa),
                                      testing::material(50.0));
  add_volume_constraint(model, c);
  add_fixed_nodes(model, model.components[c].node_sets.at("top"));
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 2.0;
  model.settings.integrator = integrator;
  finalize(model);
  model.settings.dt = dt_over_stable * stable_time_step(model);
  return model;
}

class Runaway3x : public ::testing::TestWithParam<Integrator> {};

// Three times the stable step: the guard stops the run within a few steps; the state it
// leaves is the last good one (the failing step undone), finite, with small motion.
TEST_P(Runaway3x, StoppedByTheGuardWithTheLastGoodStateKept) {
  Simulator sim(jelly(GetParam(), 3.0));
  const double edge = 0.005;  // m, the box's cell size
  Data before;
  try {
    for (int k = 0; k < 1000; ++k) {
      before = sim.data();
      sim.step();
    }
    FAIL() << "1000 steps at 3 times the stable step ran through";
  } catch (const InstabilityError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("a runaway, caught before any number overflowed"), std::string::npos) << m;
    EXPECT_NE(m.find("component 'jelly'"), std::string::npos) << m;
    EXPECT_NE(m.find("stability estimate"), std::string::npos) << m;
    EXPECT_NE(m.find("set simulation.dt smaller"), std::string::npos) << m;
    EXPECT_LT(sim.data().step, 10);  // caught as the growth starts (34x per step at 3x)
    EXPECT_EQ(sim.data().step, before.step);
    EXPECT_EQ(sim.data().time, before.time);
    for (int i = 0; i < sim.model().node_count(); ++i) {
      EXPECT_EQ(sim.data().x[i], before.x[i]) << i;
      EXPECT_EQ(sim.data().v[i], before.v[i]) << i;
      EXPECT_TRUE(sim.data().f[i].allFinite()) << i;
      EXPECT_LT((sim.data().x[i] - sim.model().rest_position[i]).norm(), edge) << i;
    }
    EXPECT_LT(sim.kinetic_energy(), 1e-3);  // J; the old criterion let it reach ~24 J
  }
}

INSTANTIATE_TEST_SUITE_P(Integrators, Runaway3x,
                         ::testing::Values(Integrator::verlet, Integrator::newton_cotes));

// At the stability estimate's own step, the same scene runs its course: the guard does not
// fire on a stable run (its largest relative step here is about 1% of an edge).
TEST(RunawayGuard, QuietAtTheStableStep) {
  Simulator sim(jelly(Integrator::verlet, 1.0));
  for (int k = 0; k < 3000; ++k) ASSERT_NO_THROW(sim.step()) << "step " << k;
}

TEST(RunawayGuard, RigidMotionIsNotARunawayButANeighbourJumpIs) {
  const Model model = testing::single_component(
      make_box(Vec3(0.02, 0.02, 0.02), {4, 4, 4}, CellType::hexa), testing::material(50.0));
  const std::vector<double>& edges = model.runaway_edge;
  for (double e : edges) EXPECT_NEAR(e, 0.005, 1e-15);
  const std::vector<Vec3>& rest = model.rest_position;
  // A translation by 10 edges and a small rotation in one step: no runaway.
  std::vector<Vec3> after(rest);
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.05, Vec3::UnitZ()).toRotationMatrix();
  for (Vec3& p : after) p = turn * p + Vec3(0.05, -0.02, 0.03);
  EXPECT_FALSE(find_runaway(model, edges, rest, after));
  // One node 1.9 edges off its neighbours on top of that: still no runaway.
  after[17] += Vec3(0.0, 0.0095, 0.0);
  EXPECT_FALSE(find_runaway(model, edges, rest, after));
  // 2.4 edges: named, with its move (against its neighbours' mean step) and edge.
  after[17] += Vec3(0.0, 0.0025, 0.0);
  const auto r = find_runaway(model, edges, rest, after);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->node, 17);
  EXPECT_NEAR(r->moved, 0.012, 0.0003);
  EXPECT_NEAR(r->edge, 0.005, 1e-15);
}

TEST(RunawayGuard, HeldNodesAreNotWatched) {
  Model model;
  const int c = add_elastic_component(model, "jelly",
                                      make_box(Vec3(0.02, 0.02, 0.02), {2, 2, 2}, CellType::hexa),
                                      testing::material(50.0));
  add_fixed_nodes(model, model.components[c].node_sets.at("top"));
  finalize(model);
  const std::vector<double>& edges = model.runaway_edge;
  for (int i : model.components[c].node_sets.at("top")) EXPECT_TRUE(std::isinf(edges[i]));
  EXPECT_EQ(edges[0], 0.01);
}

}  // namespace
}  // namespace phymul
