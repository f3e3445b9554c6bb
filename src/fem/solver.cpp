// phymul::fem::solve_static - the reference finite element solver.
//
// Formulation
//   Total Lagrangian, large deformation, static. Linear hexahedra (2x2x2 Gauss) and linear
//   tetrahedra (1 point), VTK node order. Compressible Neo-Hookean with a
//   deviatoric/volumetric split, W = mu/2 (J^(-2/3) I1 - 3) + kappa/2 (J - 1)^2,
//   mu = E / (2 (1 + nu)), kappa = E / (3 (1 - 2 nu)); or small-strain linear elasticity
//   (Law::linear), W = mu |dev eps|^2 + kappa/2 tr(eps)^2, which is its linearisation.
//   Body forces are dead loads per unit reference volume, consistently integrated.
//
// Volumetric treatment: mean dilatation (Q1/P0; Nagtegaal-Parks-Rice 1974, Simo-Taylor-
// Pister 1985). The volumetric energy of each element uses theta = v / V, its current over
// reference volume, instead of the pointwise J:
//   Pi = sum_e [ sum_g w_g W_dev(F_g) + V_e kappa/2 (theta_e - 1)^2 ] - f_ext . u.
//   Why: with full integration a trilinear hexahedron has 8 volume constraints for 3 degrees
//   of freedom per node and locks at nu = 0.499 (kappa/mu = 500); one constraint per element
//   (a constant element pressure, statically condensed) removes the locking. Because the
//   deviatoric part only sees the isochoric F, this is identical to F-bar with
//   Fbar = (theta/J)^(1/3) F, but it stays a plain energy minimisation: the tangent is the
//   exact, symmetric Hessian (dv/dx dv/dx^T kappa/V + p d2v/dx2 + deviatoric), so a
//   symmetric LDL^T solver and a consistent Newton method apply. For Law::linear the same
//   idea is the B-bar method. Linear tetrahedra have a constant J already, so this changes
//   nothing for them: they lock as nu -> 0.5 (use them with nu <= ~0.45).
//
// Solution: load steps scale the body force and the prescribed displacements together
// (factor k / load_steps). Each increment: tangent predictor, then Newton with a backtracking
// line search on the free residual norm (newton.cpp for the convergence test). Prescribed
// dofs are eliminated. K_ff has a sparsity pattern fixed once and filled in place; it is
// factorised by a supernodal multifrontal Cholesky in nested-dissection order (symbolic
// analysis once, numeric factorisation per iteration; sparse_cholesky.hpp for why not
// Eigen's SimplicialLDLT, which remains the fallback for an indefinite tangent). An increment
// that fails is bisected, up to kMaxBisections times, before the solve gives up.
//
// Reactions: internal minus external force per node (non-zero only on prescribed components
// at equilibrium).
// Several materials (Problem::materials, per cell) and nodal dead loads (Problem::nodal_force,
// scaled with the load like the body force) let a scene of several objects be one system.
#include <cmath>
#include <sstream>

#include "fem/input.hpp"
#include "fem/newton.hpp"
#include "fem/system.hpp"
#include "phymul/fem.hpp"

namespace phymul::fem {

namespace {

constexpr int kMaxBisections = 8;  // sub-increments down to 1/256 of a load step

double bounding_box_diagonal(const Mesh& mesh) {
  Eigen::AlignedBox3d box;
  for (const Vec3& p : mesh.points) box.extend(p);
  return box.diagonal().norm();
}

std::string failure_message(int step, int steps, double reached, double target,
                            const StepFailure& failure, int depth) {
  std::ostringstream out;
  out.precision(6);
  out << "fem::solve_static: load step " << step << " of " << steps
      << " did not converge (equilibrium reached at load factor " << reached << ", failed towards "
      << target;
  if (!failure.fatal) out << " with the increment bisected " << depth << " times";
  out << "): " << failure.reason;
  return out.str();
}

std::vector<Vec3> per_node(const Eigen::VectorXd& v) {
  std::vector<Vec3> out(v.size() / 3);
  for (std::size_t n = 0; n < out.size(); ++n) out[n] = v.segment<3>(3 * Eigen::Index(n));
  return out;
}

// Advances one nominal load step. A failed increment is halved (down to 1/2^kMaxBisections
// of the step); after two successes in a row it is doubled again (up to the whole step), so
// one hard stretch does not slow the rest of the step down. "" on success.
std::string advance(LoadStepper& stepper, int step, int steps) {
  const double end = double(step) / steps;
  const double nominal = 1.0 / steps;
  double increment = nominal;
  int depth = 0, successes = 0;
  while (stepper.load_factor() < end) {
    const double target = stepper.load_factor() + increment;
    // Land exactly on the step boundary instead of a round-off short of it.
    const double s1 = target > end - 1e-12 * nominal ? end : target;
    StepFailure failure;
    if (stepper.step_to(s1, failure)) {
      if (++successes >= 2 && depth > 0) {
        increment *= 2.0;
        --depth;
        successes = 0;
      }
      continue;
    }
    if (failure.fatal || depth == kMaxBisections) {
      return failure_message(step, steps, stepper.load_factor(), s1, failure, depth);
    }
    increment *= 0.5;
    ++depth;
    successes = 0;
  }
  return "";
}

}  // namespace

Result solve_static(const Problem& problem) {
  check_problem(problem);
  const PrescribedValues prescribed = prescribed_values(problem);
  System system =
      problem.materials.empty()
          ? System(problem.mesh, problem.material, prescribed.mask)
          : System(problem.mesh, problem.materials, problem.cell_material, prescribed.mask);
  Eigen::VectorXd target = Eigen::Map<const Eigen::VectorXd>(prescribed.value.data(),
                                                             Eigen::Index(prescribed.value.size()));
  const NewtonSettings settings{problem.tolerance, problem.max_newton_iterations,
                                bounding_box_diagonal(problem.mesh), problem.force_tolerance};
  NodeGeometry geometry{{}, problem.mesh.points};
  for (int dof : system.free_dofs()) geometry.group.push_back(dof / 3);
  Eigen::VectorXd load = system.body_force(problem.body_force);
  for (std::size_t n = 0; n < problem.nodal_force.size(); ++n)
    load.segment<3>(3 * Eigen::Index(n)) += problem.nodal_force[n];
  LoadStepper stepper(system, std::move(load), std::move(target), geometry, settings);
  int first = 1;
  if (problem.resume_from) {
    stepper.resume(*problem.resume_from);
    first = problem.resume_from->load_steps_done + 1;
  }

  Result result;
  result.converged = true;
  result.load_steps_done = first - 1;
  SolveState state;
  for (int step = first; step <= problem.load_steps && result.converged; ++step) {
    result.message = advance(stepper, step, problem.load_steps);
    result.converged = result.message.empty();
    if (!result.converged) break;
    result.load_steps_done = step;
    if (problem.on_load_step) {
      result.displacement = per_node(stepper.displacement());
      result.reaction = per_node(stepper.reaction());
      stepper.save(state);
      state.load_steps_done = step;
      const LoadStepReport report{step,
                                  problem.load_steps,
                                  result.displacement,
                                  result.reaction,
                                  stepper.iterations(),
                                  stepper.free_residual(),
                                  state};
      if (!problem.on_load_step(report) && step < problem.load_steps) {
        result.converged = false;
        result.stopped = true;
        result.message = "fem::solve_static: stopped after load step " + std::to_string(step) +
                         " of " + std::to_string(problem.load_steps);
      }
    }
  }
  result.displacement = per_node(stepper.displacement());
  result.reaction = per_node(stepper.reaction());
  result.newton_iterations = stepper.iterations();
  result.final_residual = stepper.free_residual();
  return result;
}

}  // namespace phymul::fem
