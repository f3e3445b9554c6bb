// The implicit steps and the implicit static solver with explicit finite elements (TLED): P
// takes the cells' stiffness at rest (their energy's Hessian there, ImplicitMatrix.*), the
// residual their exact forces, so the fixed point is the relaxation's equilibrium.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "forces/explicit_fem.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "solver/implicit_step.hpp"
#include "support/examples.hpp"
#include "support/models.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

using testing::compile_example;
using testing::largest_gap;

// Takes `steps` steps, each to 1e-10 N; the most solves a step took, or -1 after a failure.
int most_solves(Simulator& sim, int steps) {
  int most = 0;
  for (int k = 0; k < steps; ++k) {
    sim.step();
    if (!(implicit_residual_force(sim.data()) < 1e-10)) {
      ADD_FAILURE() << "t " << sim.data().time << ": " << implicit_residual_force(sim.data());
      return -1;
    }
    most = std::max(most, implicit_iterations(sim.data()));
  }
  return most;
}

// The finite-element cube compressed by 6 mm (15 %, Neo-Hookean, nu = 0.45): the implicit
// static solver's equilibrium is the relaxation's; steps at 100 times the explicit limit
// converge at every step and end at rest on it.
TEST(ImplicitFem, CompressedCubeEndsAtTheRelaxationsEquilibrium) {
  Simulator relaxed(compile_example("fem_cube.yaml", SolveMode::static_equilibrium,
                                    Integrator::verlet, StaticSolver::relaxation));
  const StaticResult a = relaxed.solve_static();
  ASSERT_TRUE(a.converged) << a.residual;
  const Model& m = relaxed.model();
  const double moved = largest_gap(relaxed.data().x, m.rest_position);
  ASSERT_GT(moved, 5.99e-3);  // the top pushed down 6 mm

  Simulator implicit(compile_example("fem_cube.yaml", SolveMode::static_equilibrium,
                                     Integrator::verlet, StaticSolver::implicit));
  const StaticResult b = implicit.solve_static();
  ASSERT_TRUE(b.converged) << b.residual;
  const double gap = largest_gap(implicit.data().x, relaxed.data().x);
  EXPECT_LT(gap, 1e-6 * moved) << gap / moved;

  Model dynamic = compile_example("fem_cube.yaml", SolveMode::dynamic, Integrator::implicit,
                                  StaticSolver::relaxation);
  const double limit = stable_time_step(dynamic);
  Simulator steps(dynamic);
  steps.set_dt(100.0 * limit);
  const int count = int(std::lround(3.0 / steps.dt()));  // pushed over 1 s, then held
  const int most = most_solves(steps, count);
  ASSERT_GT(most, 0);
  const double settled = largest_gap(steps.data().x, relaxed.data().x);
  EXPECT_LT(settled, 1e-6 * moved) << settled / moved;
  std::printf(
      "fem cube: moved %.3g mm; relaxation %ld iterations, implicit statics %ld (%.2g of the "
      "motion); %d steps of %.3g ms (100x the explicit %.3g us), at most %d solves, at rest "
      "%.2g of the motion away\n",
      moved * 1e3, a.iterations, b.iterations, gap / moved, count, steps.dt() * 1e3, limit * 1e6,
      most, settled / moved);
}

// The largest angle (rad) between a cell's deformation and its rest shape, over the cells.
double most_turned(const Model& model, const Data& d) {
  std::vector<Eigen::Quaterniond> q(model.explicit_fem[0].volume.size(),
                                    Eigen::Quaterniond::Identity());
  fit_cell_rotations(model.explicit_fem[0], model.rest_position, d.x, q);
  double most = 0.0;
  for (const Eigen::Quaterniond& r : q)
    most = std::max(most, r.angularDistance(Eigen::Quaterniond::Identity()));
  return most;
}

// The cantilever of fem_newton_cantilever.yaml (100 x 20 x 20 mm, E = 100 kPa) bent by its
// weight: its cells turn by up to 0.44 rad, where the stiffness at rest alone, not turned with
// them, made the iterations diverge at 5 ms steps. The implicit static solver and 5 ms steps
// (60 times the explicit limit) with damping end at the relaxation's equilibrium.
TEST(ImplicitFem, BentCantileverEndsAtTheRelaxationsEquilibrium) {
  Simulator relaxed(compile_example("fem_newton_cantilever.yaml", SolveMode::static_equilibrium,
                                    Integrator::verlet, StaticSolver::relaxation));
  const StaticResult a = relaxed.solve_static();
  ASSERT_TRUE(a.converged) << a.residual;
  const Model& m = relaxed.model();
  const double moved = largest_gap(relaxed.data().x, m.rest_position);
  const double turned = most_turned(m, relaxed.data());
  ASSERT_GT(turned, 0.4);

  Simulator implicit(compile_example("fem_newton_cantilever.yaml", SolveMode::static_equilibrium,
                                     Integrator::verlet, StaticSolver::implicit));
  const StaticResult b = implicit.solve_static();
  ASSERT_TRUE(b.converged) << b.residual;
  const double gap = largest_gap(implicit.data().x, relaxed.data().x);
  EXPECT_LT(gap, 1e-6 * moved) << gap / moved;

  Scene scene = load_scene(testing::source_dir() / "examples" / "fem_newton_cantilever.yaml");
  scene.simulation.mode = SolveMode::dynamic;
  scene.simulation.integrator = Integrator::implicit;
  scene.simulation.damping = 10.0;
  scene.simulation.implicit_iterations = 2000;
  scene.simulation.implicit_tolerance = 1e-10;
  Simulator steps(compile_scene(scene));
  const double limit = stable_time_step(steps.model());
  steps.set_dt(5e-3);
  const int count = 800;  // 4 s
  const int most = most_solves(steps, count);
  ASSERT_GT(most, 0);
  const double settled = largest_gap(steps.data().x, relaxed.data().x);
  EXPECT_LT(settled, 1e-6 * moved) << settled / moved;
  std::printf(
      "cantilever: tip moved %.3g mm, cells turned up to %.3g rad; relaxation %ld iterations, "
      "implicit statics %ld (%.2g of the motion); %d steps of 5 ms (%.0fx the explicit "
      "limit), at most %d solves, at rest %.2g of the motion away\n",
      moved * 1e3, turned, a.iterations, b.iterations, gap / moved, count, 5e-3 / limit, most,
      settled / moved);
}

}  // namespace
}  // namespace phymul
