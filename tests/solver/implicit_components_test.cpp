// The implicit steps and the implicit static solver with the components beside the elastic
// shape memory: active fibres and rigid bodies. Each finds the kinetic relaxation's
// equilibrium (the same forces, so the same fixed point), steps far beyond the explicit limit
// settle on it, and a free body keeps its momenta.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "solver/implicit_step.hpp"
#include "support/examples.hpp"
#include "support/models.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

using testing::largest_gap;

// The muscle example's strip without its bones: 1 x 1 x 4 cm of 300 N/m memories hanging from
// its fixed top, fibres along its length (600 N/m a segment) fully active, shortening by up
// to 30 %: they lift the strip against its weight.
Model contracted_strip() {
  Model model;
  const int c = add_elastic_component(
      model, "muscle", make_box(Vec3(0.01, 0.01, 0.04), {2, 2, 8}, CellType::hexa), [] {
        MaterialSpec m = testing::material(300.0);
        m.density = 1060.0;
        return m;
      }());
  add_fixed_nodes(model, model.components[c].node_sets.at("top"));
  add_fibres(model, c, Vec3::UnitZ(), 600.0, 0.3,
             Schedule{{0.0, 1.0}, {Vec3::Zero(), Vec3(1.0, 0.0, 0.0)}});
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 10.0;
  model.settings.implicit_iterations = 2000;
  model.settings.implicit_tolerance = 1e-11;
  finalize(model);
  return model;
}

Model statics(Model model, StaticSolver solver) {
  model.settings.mode = SolveMode::static_equilibrium;
  model.settings.solver = solver;
  model.settings.tolerance = 1e-11;
  model.settings.max_iterations = 400000;
  finalize(model);
  return model;
}

TEST(ImplicitFibres, StaticsAndLargeStepsFindTheRelaxationsEquilibrium) {
  Simulator relaxed(statics(contracted_strip(), StaticSolver::relaxation));
  const StaticResult a = relaxed.solve_static();
  ASSERT_TRUE(a.converged) << a.residual;
  const Model& m = relaxed.model();
  // The fibres shorten the strip: its free end rises (the weight alone would lower it).
  double lift = -1.0;
  for (int i : m.components[0].node_sets.at("bottom"))
    lift = std::max(lift, relaxed.data().x[size_t(i)].z() - m.rest_position[size_t(i)].z());
  ASSERT_GT(lift, 1e-3);
  const double moved = largest_gap(relaxed.data().x, m.rest_position);

  Simulator implicit(statics(contracted_strip(), StaticSolver::implicit));
  const StaticResult b = implicit.solve_static();
  ASSERT_TRUE(b.converged) << b.residual;
  const double gap = largest_gap(implicit.data().x, relaxed.data().x);
  EXPECT_LT(gap, 1e-6 * moved) << gap / moved;

  Model dynamic = contracted_strip();
  dynamic.settings.integrator = Integrator::implicit;
  dynamic.settings.dt = 100.0 * stable_time_step(dynamic);
  finalize(dynamic);
  Simulator steps(dynamic);
  int most = 0;
  for (int k = 0; k < 200; ++k) {
    steps.step();
    ASSERT_LT(implicit_residual_force(steps.data()), 1e-11) << "step " << k;
    most = std::max(most, implicit_iterations(steps.data()));
  }
  const double settled = largest_gap(steps.data().x, relaxed.data().x);
  EXPECT_LT(settled, 1e-6 * moved) << settled / moved;
  // Anderson-accelerated: 33 solves at most here, 187 without the acceleration.
  EXPECT_LE(most, 40);
  std::printf(
      "fibres: lift %.3g mm; relaxation %ld steps, implicit statics %ld (%.2g of the "
      "motion); 100x steps at most %d solves, at rest %.2g of the motion away\n",
      lift * 1e3, a.iterations, b.iterations, gap / moved, most, settled / moved);
}

// The muscle example whole (docs/model.md): an active strip doubled with a held bone above and
// a free one below, its volume kept, fully active at the scene's end. The implicit static
// solver's equilibrium is the relaxation's; the implicit steps at ten times the example's dt
// converge at every step of the whole run and end at rest there.
TEST(ImplicitRigidBodies, MuscleExampleEndsAtTheRelaxationsEquilibrium) {
  auto compiled = [](SolveMode mode, Integrator integrator, StaticSolver solver) {
    return testing::compile_example("muscle.yaml", mode, integrator, solver);
  };
  Simulator relaxed(
      compiled(SolveMode::static_equilibrium, Integrator::verlet, StaticSolver::relaxation));
  const StaticResult a = relaxed.solve_static();
  ASSERT_TRUE(a.converged) << a.residual;
  const Model& m = relaxed.model();
  const double moved = largest_gap(relaxed.data().x, m.rest_position);
  ASSERT_GT(moved, 5e-3);  // the lower bone rose by millimetres

  Simulator implicit(
      compiled(SolveMode::static_equilibrium, Integrator::verlet, StaticSolver::implicit));
  const StaticResult b = implicit.solve_static();
  ASSERT_TRUE(b.converged) << b.residual;
  const double gap = largest_gap(implicit.data().x, relaxed.data().x);
  EXPECT_LT(gap, 1e-6 * moved) << gap / moved;

  Simulator steps(compiled(SolveMode::dynamic, Integrator::implicit, StaticSolver::relaxation));
  steps.set_dt(10.0 * steps.dt());
  int most = 0, count = 0;
  while (steps.data().time < 6.0) {  // the scene's 2.5 s, then at rest
    steps.step();
    ASSERT_LT(implicit_residual_force(steps.data()), 1e-10) << "t " << steps.data().time;
    most = std::max(most, implicit_iterations(steps.data())), ++count;
  }
  const double settled = largest_gap(steps.data().x, relaxed.data().x);
  EXPECT_LT(settled, 1e-6 * moved) << settled / moved;
  std::printf(
      "muscle: moved %.3g mm; relaxation %ld steps, implicit statics %ld (%.2g of the "
      "motion); %d steps of %.3g ms, at most %d solves, at rest %.2g of the motion away\n",
      moved * 1e3, a.iterations, b.iterations, gap / moved, count, steps.dt() * 1e3, most,
      settled / moved);
}

// A lone free body, spinning about a tilted axis and drifting, no gravity and no damping:
// backward Euler keeps its momentum and angular momentum (no force, no torque) and moves the
// centre uniformly, where the rotation's energy may only fall.
TEST(ImplicitRigidBodies, AFreeBodyKeepsItsMomenta) {
  Model model;
  add_rigid_component(model, "bone", make_box(Vec3(0.04, 0.02, 0.01), {4, 2, 1}, CellType::hexa),
                      [] {
                        MaterialSpec m;
                        m.density = 1900.0;
                        return m;
                      }());
  model.settings.integrator = Integrator::implicit;
  model.settings.implicit_tolerance = 1e-12;
  model.settings.implicit_iterations = 200;
  model.settings.dt = 0.01;
  finalize(model);
  Simulator sim(model);
  RigidBodyState& body = sim.data().bodies[0];
  const Vec3 p0(1e-4, -2e-4, 3e-4), L0(2e-6, 1e-6, -3e-6);
  body.momentum = p0;
  body.angular_momentum = L0;
  const Vec3 c0 = body.center;
  auto energy = [&] {
    const RigidBody& r = sim.model().rigid_bodies[0];
    const Eigen::Matrix3d R = sim.data().bodies[0].orientation.toRotationMatrix();
    const Vec3 l = R.transpose() * sim.data().bodies[0].angular_momentum;
    return 0.5 * l.dot(l.cwiseQuotient(r.inertia));
  };
  double previous = energy();
  int most = 0;
  for (int k = 0; k < 200; ++k) {
    sim.step();
    most = std::max(most, implicit_iterations(sim.data()));
    const RigidBodyState& now = sim.data().bodies[0];
    // A step ends with its residual force below the tolerance (its moment below the tolerance
    // times the body's size): each step's momenta within dt times that of the last's.
    const double h = sim.dt(), tolerance = sim.model().settings.implicit_tolerance;
    ASSERT_LE(implicit_residual_force(sim.data()), tolerance)
        << "step " << k << ", " << implicit_iterations(sim.data()) << " solves";
    const double steps = k + 1.0, size = sim.model().rigid_bodies[0].size;
    ASSERT_LE((now.momentum - p0).norm(), steps * h * tolerance) << "step " << k;
    ASSERT_LE((now.angular_momentum - L0).norm(), steps * h * tolerance * size) << "step " << k;
    ASSERT_LE(energy(), previous * (1.0 + 1e-12)) << "step " << k;
    previous = energy();
  }
  const double mass = sim.model().rigid_bodies[0].mass;
  EXPECT_LT((sim.data().bodies[0].center - (c0 + 2.0 * p0 / mass)).norm(), 1e-12);
  const Eigen::AngleAxisd turned(sim.data().bodies[0].orientation *
                                 sim.model().rigid_bodies[0].rest_orientation.conjugate());
  std::printf("free body: turned %.2f rad in 2 s, at most %d solves a step\n", turned.angle(),
              most);
}

}  // namespace
}  // namespace phymul
