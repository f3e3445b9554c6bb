// Backward-Euler steps by local/global iterations (integrator: implicit): stable far beyond
// the explicit limit, converging to the model's own equilibrium, the same bits on any number
// of threads.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "solver/implicit_step.hpp"
#include "support/models.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

using testing::largest_gap;

// The simulator test's hanging cube: 27 g of 5 N/m memories, the top fixed, gravity.
Model hanging_cube(Integrator integrator) {
  Model model;
  const int c = add_elastic_component(model, "cube",
                                      make_box(Vec3(0.02, 0.02, 0.02), {3, 3, 3}, CellType::hexa),
                                      testing::material(5.0));
  add_fixed_nodes(model, model.components[c].node_sets.at("top"));
  model.gravity = Vec3(0, 0, -9.81);
  model.settings.integrator = integrator;
  model.settings.implicit_iterations = 200;
  model.settings.implicit_tolerance = 1e-12;
  finalize(model);
  return model;
}

// Kinetic + elastic + gravitational energy (J), the potential's zero at rest.
double total_energy(const Model& model, const Data& d) {
  double e = kinetic_energy(model, d) + d.shape_memory_energy;
  for (int i = 0; i < model.node_count(); ++i)
    e -= model.mass[size_t(i)] * model.gravity.dot(d.x[size_t(i)] - model.rest_position[size_t(i)]);
  return e;
}

double largest_displacement(const Model& model, const std::vector<Vec3>& x) {
  return largest_gap(x, model.rest_position);
}

// The cube released from rest at 100 times the explicit stability limit: backward Euler
// takes energy out at every step (never in), nothing blows up, and it comes to rest at the
// static equilibrium.
TEST(ImplicitSteps, HundredTimesTheStabilityLimitDissipatesAndSettles) {
  Model model = hanging_cube(Integrator::implicit);
  const double limit = stable_time_step(model);
  model.settings.dt = 100.0 * limit;
  Simulator sim(model);
  double previous = total_energy(sim.model(), sim.data());
  const double weight_scale = 0.027 * 9.81 * 0.01;  // J: the weight over a centimetre
  for (int k = 0; k < 400; ++k) {
    sim.step();
    ASSERT_LT(implicit_residual_force(sim.data()), 1e-12) << "step " << k;
    const double e = total_energy(sim.model(), sim.data());
    ASSERT_TRUE(std::isfinite(e));
    // Dissipative at every step (to the residual's round-off).
    ASSERT_LE(e, previous + 1e-12 * weight_scale) << "step " << k;
    previous = e;
  }
  EXPECT_LT(previous, -0.1 * weight_scale);  // it sagged, and lost what it gained
  // At rest: the kinetic energy is a vanishing share of the potential drop.
  EXPECT_LT(kinetic_energy(sim.model(), sim.data()), 1e-12 * std::abs(previous));
  // The explicit scheme at that step blows up.
  Model explicit_model = hanging_cube(Integrator::verlet);
  explicit_model.settings.dt = 100.0 * limit;
  Simulator verlet(explicit_model);
  EXPECT_THROW(for (int k = 0; k < 100; ++k) verlet.step(), InstabilityError);
}

// With only fixed nodes and gravity, the steps' fixed point is the static equilibrium: the
// implicit run ends where the static relaxation (full forces, the rotations' derivative
// included) ends. Had the iteration dropped the rotation-derivative forces it would stop at
// another model's equilibrium.
TEST(ImplicitSteps, ComeToRestAtTheStaticEquilibrium) {
  Model statics = hanging_cube(Integrator::verlet);
  statics.settings.mode = SolveMode::static_equilibrium;
  statics.settings.tolerance = 1e-12;
  statics.settings.max_iterations = 400000;
  finalize(statics);
  Simulator relaxed(statics);
  ASSERT_TRUE(relaxed.solve_static().converged);

  Model model = hanging_cube(Integrator::implicit);
  model.settings.dt = 0.5;  // s: about 2000 times the explicit limit
  Simulator sim(model);
  for (int k = 0; k < 60; ++k) sim.step();
  EXPECT_LT(implicit_residual_force(sim.data()), 1e-12);
  const double sag = largest_displacement(sim.model(), relaxed.data().x);
  EXPECT_GT(sag, 1e-3);
  const double gap = largest_gap(sim.data().x, relaxed.data().x);
  EXPECT_LT(gap, 1e-6 * sag) << gap / sag;
  std::printf("implicit against static equilibrium: %.3g of the largest displacement\n", gap / sag);
  EXPECT_LT(sim.max_residual_force(), 1e-10);
}

// The implicit static solver (solver: implicit) finds the relaxation's equilibrium, with
// the rotations' derivative carried, in a few dozen solves where the relaxation takes
// thousands of steps.
TEST(ImplicitStatics, FindTheRelaxationsEquilibrium) {
  auto statics = [](StaticSolver solver) {
    Model model = hanging_cube(Integrator::verlet);
    model.settings.mode = SolveMode::static_equilibrium;
    model.settings.solver = solver;
    model.settings.tolerance = 1e-12;
    model.settings.max_iterations = 400000;
    finalize(model);
    return model;
  };
  Simulator relaxed(statics(StaticSolver::relaxation));
  const StaticResult a = relaxed.solve_static();
  ASSERT_TRUE(a.converged);
  Simulator implicit(statics(StaticSolver::implicit));
  const StaticResult b = implicit.solve_static();
  ASSERT_TRUE(b.converged) << b.residual;
  EXPECT_LT(b.residual, 1e-12);
  const double sag = largest_displacement(relaxed.model(), relaxed.data().x);
  const double gap = largest_gap(implicit.data().x, relaxed.data().x);
  EXPECT_LT(gap, 1e-6 * sag) << gap / sag;
  EXPECT_LT(b.iterations * 20, a.iterations);  // at most 20 solves an iteration
  std::printf("static: relaxation %ld steps, implicit %ld steps; gap %.3g of the sag\n",
              a.iterations, b.iterations, gap / sag);
}

// A 16^3 block (4913 nodes: the force pass runs in parallel) with its volume kept, damping
// and gravity: one and two threads give the same bits.
void one_and_two_threads_give_bit_identical_states(ElasticModel elasticity) {
  MaterialSpec material = testing::material(20.0);
  if (elasticity == ElasticModel::fem) {
    material.model = ElasticModel::fem;
    material.young = 14.9e3;
    material.poisson = 0.45;
  }
  Model model;
  const int c = add_elastic_component(
      model, "block", make_box(Vec3(0.08, 0.08, 0.08), {16, 16, 16}, CellType::hexa), material);
  add_volume_constraint(model, c);
  add_fixed_nodes(model, model.components[c].node_sets.at("bottom"));
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 5.0;
  model.settings.integrator = Integrator::implicit;
  model.settings.implicit_iterations = 4;
  finalize(model);
  model.settings.dt = 20.0 * stable_time_step(model);
  finalize(model);
  ASSERT_EQ(model.explicit_fem.empty(), elasticity == ElasticModel::shape_memory);
  auto run = [&](int threads) {
    const int previous = omp_get_max_threads();
    omp_set_num_threads(threads);
    Simulator sim(model);
    for (int k = 0; k < 4; ++k) sim.step();
    omp_set_num_threads(previous);
    return sim.data();
  };
  const Data one = run(1), two = run(2);
  const size_t bytes = one.x.size() * sizeof(Vec3);
  EXPECT_EQ(std::memcmp(one.x.data(), two.x.data(), bytes), 0);
  EXPECT_EQ(std::memcmp(one.v.data(), two.v.data(), bytes), 0);
  EXPECT_EQ(std::memcmp(one.f.data(), two.f.data(), bytes), 0);
  EXPECT_GT((one.x.back() - model.rest_position.back()).norm(), 1e-5);
  double turned = 0.0;
  for (const Eigen::Quaterniond& q : one.cell_rotation)
    turned = std::max(turned, q.angularDistance(Eigen::Quaterniond::Identity()));
  if (elasticity == ElasticModel::fem) {
    EXPECT_GT(turned, 0.02);  // P took turned cells
  }
}

// Shape memory, and explicit finite elements (their cells' rotations fitted and P refactorised
// as they turn, in the same steps on either count).
TEST(ImplicitSteps, OneAndTwoThreadsGiveBitIdenticalStates) {
  for (const ElasticModel elasticity : {ElasticModel::shape_memory, ElasticModel::fem}) {
    SCOPED_TRACE(int(elasticity));
    one_and_two_threads_give_bit_identical_states(elasticity);
  }
}

// The volume constraint holds through the solve: the enclosed volume stays at its target to
// round-off, and the residual (less the constraint's pressure) converges. (At ten times the
// explicit limit a step takes tens to hundreds of iterations: the matrix lacks the pressure's
// curvature, see docs/implicit.md.)
TEST(ImplicitSteps, VolumeConstraintHoldsAndResidualConverges) {
  Model model;
  const int c = add_elastic_component(model, "block",
                                      make_box(Vec3(0.04, 0.04, 0.04), {4, 4, 4}, CellType::hexa),
                                      testing::material(200.0));
  add_volume_constraint(model, c);
  add_fixed_nodes(model, model.components[c].node_sets.at("top"));
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 6.0;
  model.settings.integrator = Integrator::implicit;
  model.settings.implicit_iterations = 1000;
  model.settings.implicit_tolerance = 1e-10;
  finalize(model);
  model.settings.dt = 10.0 * stable_time_step(model);
  finalize(model);
  Simulator sim(model);
  const double target = model.volumes[0].target_volume;
  for (int k = 0; k < 30; ++k) {
    sim.step();
    ASSERT_LT(implicit_residual_force(sim.data()), 1e-10) << "step " << k;
    const double v = enclosed_volume(sim.data().x, model.volumes[0].triangles);
    ASSERT_NEAR(v, target, 1e-10 * target) << "step " << k;
  }
  EXPECT_GT(largest_displacement(sim.model(), sim.data().x), 1e-4);
}

// Two blocks side by side, their facing nodes doubled (Fig. 1b) and one block's base fixed:
// each group moves as one (the same bits), the other block hangs from the first, and the
// residual converges.
TEST(ImplicitSteps, DoubledNodesMoveAsOne) {
  Model model;
  const Mesh box = make_box(Vec3(0.02, 0.02, 0.02), {2, 2, 2}, CellType::hexa);
  const int a = add_elastic_component(model, "a", box, testing::material(20.0));
  Mesh shifted = box;
  for (Vec3& p : shifted.points) p.x() += 0.02;
  const int b = add_elastic_component(model, "b", shifted, testing::material(20.0));
  add_doubled_nodes(model, coincident_pairs(model, model.components[a].node_sets.at("right"),
                                            model.components[b].node_sets.at("left"), 1e-9));
  add_fixed_nodes(model, model.components[a].node_sets.at("left"));
  model.gravity = Vec3(0, 0, -9.81);
  model.settings.integrator = Integrator::implicit;
  model.settings.implicit_iterations = 500;
  model.settings.implicit_tolerance = 1e-10;
  finalize(model);
  ASSERT_EQ(model.doubled.rows(), 9);
  model.settings.dt = 30.0 * stable_time_step(model);
  finalize(model);
  Simulator sim(model);
  for (int k = 0; k < 30; ++k) {
    sim.step();
    ASSERT_LT(implicit_residual_force(sim.data()), 1e-10) << "step " << k;
  }
  for (int g = 0; g < model.doubled.rows(); ++g) {
    const auto group = model.doubled.row(g);
    for (int i : group) {
      EXPECT_EQ(sim.data().x[size_t(i)], sim.data().x[size_t(group[0])]);
      EXPECT_EQ(sim.data().v[size_t(i)], sim.data().v[size_t(group[0])]);
    }
  }
  // The far block sags: it hangs from the doubled nodes alone.
  EXPECT_LT(sim.data().x.back().z() - model.rest_position.back().z(), -1e-3);
}

// Every example scene (examples/, its sweep files aside): ten steps at ten times the scene's
// own dt, each converging to 1e-8 N (the needle's insertion:
// tests/solver/implicit_needle_test.cpp).
TEST(ImplicitSteps, ExampleScenesConverge) {
  const std::filesystem::path examples = testing::source_dir() / "examples";
  std::vector<std::string> scenes;
  for (const auto& e : std::filesystem::recursive_directory_iterator(examples)) {
    const std::string name = std::filesystem::relative(e.path(), examples).string();
    if (e.path().extension() == ".yaml" && !name.starts_with("sweeps/")) scenes.push_back(name);
  }
  std::sort(scenes.begin(), scenes.end());
  int supported = 0;
  for (const std::string& name : scenes) {
    SCOPED_TRACE(name);
    Scene scene = load_scene(examples / name);
    scene.simulation.integrator = Integrator::implicit;
    scene.simulation.mode = SolveMode::dynamic;
    scene.simulation.implicit_iterations = 2000;
    scene.simulation.implicit_tolerance = 1e-8;
    const Model model = compile_scene(scene);
    ++supported;
    Simulator sim(model);
    sim.set_dt(10.0 * sim.dt());
    int most = 0;
    for (int k = 0; k < 10; ++k) {
      sim.step();
      EXPECT_LT(implicit_residual_force(sim.data()), 1e-8) << "step " << k;
      EXPECT_LT(implicit_iterations(sim.data()), 2000) << "step " << k;
      most = std::max(most, implicit_iterations(sim.data()));
    }
    std::printf("%s: %d nodes, dt %.3g s, at most %d iterations a step\n", name.c_str(),
                sim.model().node_count(), sim.dt(), most);
  }
  EXPECT_GE(supported, 25);
}

}  // namespace
}  // namespace phymul
