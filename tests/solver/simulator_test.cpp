#include <gtest/gtest.h>

#include <random>

#include "phymul/simulation.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

// Free body, small random velocities with no net momentum: a vibration.
Simulator vibrating_block(Integrator integrator, double dt_fraction) {
  Model model;
  add_elastic_component(model, "block", make_box(Vec3(0.04, 0.03, 0.02), {4, 3, 2}, CellType::hexa),
                        testing::material(30.0));
  model.settings.integrator = integrator;
  finalize(model);
  model.settings.dt = dt_fraction * stable_time_step(model);
  Simulator sim(model);
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0.0, 1e-3);
  Vec3 mean = Vec3::Zero();
  for (Vec3& v : sim.data().v) v = testing::random_vec3(n, rng), mean += v;
  mean /= double(sim.data().v.size());
  for (Vec3& v : sim.data().v) v -= mean;
  return sim;
}

double total_energy(const Simulator& sim) {
  return sim.kinetic_energy() + sim.data().shape_memory_energy;
}

TEST(Simulator, UndampedVerletConservesEnergy) {
  Simulator sim = vibrating_block(Integrator::verlet, 0.1);
  const double e0 = total_energy(sim);
  double worst = 0.0;
  for (int k = 0; k < 5000; ++k) {
    sim.step();
    worst = std::max(worst, std::abs(total_energy(sim) / e0 - 1.0));
  }
  // Measured 4e-4 over 5000 steps (about 50 periods of the fastest mode); the rotation
  // derivative the reaction form leaves out is second order in these 1 mm/s amplitudes.
  EXPECT_LT(worst, 2e-3);
}

TEST(Simulator, ReactionFormKeepsMomentumOfAFreeBody) {
  Simulator sim = vibrating_block(Integrator::verlet, 0.3);
  auto momentum = [&] {
    Vec3 p = Vec3::Zero();
    for (int i = 0; i < sim.model().node_count(); ++i) p += sim.model().mass[i] * sim.data().v[i];
    return p;
  };
  const Vec3 p0 = momentum();
  double scale = 0.0;
  for (int i = 0; i < sim.model().node_count(); ++i)
    scale += sim.model().mass[i] * sim.data().v[i].norm();
  for (int k = 0; k < 1000; ++k) sim.step();
  // Round-off of 1000 steps of force sums: about 1e-16 per step and node.
  EXPECT_LT((momentum() - p0).norm(), 1e-10 * scale);
}

Model hanging_cube(Integrator integrator) {
  Model model;
  const int c = add_elastic_component(model, "cube",
                                      make_box(Vec3(0.02, 0.02, 0.02), {3, 3, 3}, CellType::hexa),
                                      testing::material(5.0));
  add_fixed_nodes(model, model.components[c].node_sets.at("top"));
  model.gravity = Vec3(0, 0, -9.81);
  model.settings.integrator = integrator;
  model.settings.mode = SolveMode::static_equilibrium;
  model.settings.tolerance = 1e-11;
  model.settings.max_iterations = 200000;
  finalize(model);
  return model;
}

TEST(Simulator, StaticEquilibriumIsTheSameFromBothSchemes) {
  Simulator verlet(hanging_cube(Integrator::verlet));
  Simulator newton_cotes(hanging_cube(Integrator::newton_cotes));
  const StaticResult a = verlet.solve_static();
  const StaticResult b = newton_cotes.solve_static();
  ASSERT_TRUE(a.converged) << a.residual;
  ASSERT_TRUE(b.converged) << b.residual;
  double sag = 0.0, gap = 0.0;
  for (int i = 0; i < verlet.model().node_count(); ++i) {
    sag = std::max(sag, (verlet.data().x[i] - verlet.model().rest_position[i]).norm());
    gap = std::max(gap, (verlet.data().x[i] - newton_cotes.data().x[i]).norm());
  }
  EXPECT_GT(sag, 1e-3);  // 27 g on 5 N/m springs: millimetres of sag
  // Residual 1e-11 N over the softest global stiffness (~0.1 N/m, the cube swinging)
  // bounds each solution's error near 1e-10 m.
  EXPECT_LT(gap, 1e-7 * sag);
  // Equilibrium: the fixed top carries the whole weight.
  const Model& m = verlet.model();
  double weight = 0.0;
  for (double mass : m.mass) weight += mass * 9.81;
  double support = 0.0;
  for (int i : m.components[0].node_sets.at("top")) support += verlet.data().f[i].z();
  EXPECT_NEAR(support, -weight, 1e-5 * weight);
}

TEST(Simulator, FixedNodesStayExactlyFixed) {
  Simulator sim(hanging_cube(Integrator::verlet));
  for (int k = 0; k < 200; ++k) sim.step();
  for (int i : sim.model().components[0].node_sets.at("top")) {
    EXPECT_EQ(sim.data().x[i].x(), sim.model().rest_position[i].x());
    EXPECT_EQ(sim.data().x[i].y(), sim.model().rest_position[i].y());
    EXPECT_EQ(sim.data().x[i].z(), sim.model().rest_position[i].z());
  }
}

TEST(Simulator, InstabilityIsReportedWithNodeAndAdvice) {
  Model model = hanging_cube(Integrator::verlet);
  model.settings.dt = 5.0 * stable_time_step(model);
  Simulator sim(model);
  try {
    for (int k = 0; k < 100000; ++k) sim.step();
    FAIL() << "a step 5 times the stability limit ran 100000 steps";
  } catch (const InstabilityError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("node"), std::string::npos) << m;
    EXPECT_NE(m.find("component 'cube'"), std::string::npos) << m;
    EXPECT_NE(m.find("dt smaller"), std::string::npos) << m;
    EXPECT_GE(e.node, 0);
  }
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// A cube squeezed between a fixed base and a pushed top with its volume kept: at equilibrium
// the supports' reactions, volume pressure included, balance (no other load acts).
TEST(Simulator, SupportReactionsBalanceAtEquilibrium) {
  Model model;
  const int c = add_elastic_component(model, "cube",
                                      make_box(Vec3(0.02, 0.02, 0.02), {3, 3, 3}, CellType::hexa),
                                      testing::material(10.0));
  add_volume_constraint(model, c);
  add_fixed_nodes(model, model.components[c].node_sets.at("bottom"));
  add_prescribed_displacement(model, {model.components[c].node_sets.at("top"),
                                      {true, true, true},
                                      Schedule::constant(Vec3(0, 0, -0.002))});
  model.settings.tolerance = 1e-10;
  finalize(model);
  Simulator sim(model);
  ASSERT_TRUE(sim.relax(0.0, 200000).converged);
  const std::vector<Vec3> reaction = sim.support_reactions();
  Vec3 top = Vec3::Zero(), bottom = Vec3::Zero();
  for (int i : model.components[c].node_sets.at("top")) top += reaction[i];
  for (int i : model.components[c].node_sets.at("bottom")) bottom += reaction[i];
  EXPECT_LT(top.z(), -1e-3);  // the top plate pushes down on the cube
  EXPECT_LT((top + bottom).norm(), 1e-6 * std::abs(top.z()));
}

}  // namespace
}  // namespace phymul
