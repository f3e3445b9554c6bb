// One load increment of the static solve: a tangent predictor followed by Newton iterations
// with a backtracking line search on the free residual norm.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "fem/linear_solver.hpp"
#include "fem/system.hpp"

namespace phymul::fem {

struct NewtonSettings {
  double tolerance = 1e-10;   // relative to the reaction / load scale
  int max_iterations = 30;    // Newton corrections per increment
  double length_scale = 1.0;  // m, mesh bounding-box diagonal (floor of the update test)
  double force_tolerance = std::numeric_limits<double>::infinity();  // N, absolute cap
};

using StepFailure = FactorFailure;

class LoadStepper {
 public:
  // body: nodal body force at full load; target: prescribed values at full load (all dofs);
  // geometry: the node of each free dof (for the fill-reducing order).
  LoadStepper(System& system, Eigen::VectorXd body, Eigen::VectorXd target,
              const NodeGeometry& geometry, NewtonSettings settings);

  // Moves the equilibrium from the current load factor to s1. On failure the previous
  // equilibrium is restored and `failure` says why.
  bool step_to(double s1, StepFailure& failure);

  double load_factor() const { return s_; }
  const Eigen::VectorXd& displacement() const { return u_; }
  Eigen::VectorXd reaction() const;               // internal minus external force, all dofs
  double free_residual() const;                   // largest free residual component, N
  int iterations() const { return iterations_; }  // Newton corrections, predictors excluded

  // All the next load steps read (SolveState; load_steps_done is the caller's), and going on
  // from such a state of a stepper of the same system.
  void save(SolveState& state) const;
  void resume(const SolveState& state);

 private:
  Eigen::VectorXd free_residual_vector(double s) const;
  double threshold(double s) const;
  double update_tolerance() const;
  bool factorize(StepFailure& failure);
  bool predict(double s1, StepFailure& failure);
  bool line_search(const Eigen::VectorXd& residual, double s1, double& step_norm);
  void restore(const Eigen::VectorXd& u, double s);

  System& system_;
  Eigen::VectorXd body_;
  Eigen::VectorXd target_;
  NewtonSettings settings_;
  std::unique_ptr<TangentSolver> solver_;  // none when every dof is prescribed
  // The factorisation holds a tangent of the current equilibrium (or of the last Newton
  // iterate before it), good enough for the next predictor.
  bool factor_current_ = false;
  std::vector<double> factored_;  // K_ff's values the factorisation was made from
  // What the tangent predictor of the last increment missed (all dofs; its second-order
  // term) and that increment's size: the next predictor adds it, scaled to its increment.
  Eigen::VectorXd predicted_;
  Eigen::VectorXd curvature_;
  double curvature_increment_ = 0.0;  // 0: none (first increment, or after a failure)
  Eigen::VectorXd u_;
  double s_ = 0.0;
  int iterations_ = 0;
};

}  // namespace phymul::fem
