// Newton's method for one load increment.
//
// Convergence: the largest free residual component is at most tolerance * max(reaction norm,
// external load norm), with an absolute floor of 1e-12 N (a load-free or purely rigid state
// has a zero scale and a round-off residual) and at most NewtonSettings::force_tolerance (N,
// a scene's tolerance), AND the last update was below
// sqrt(tolerance) * max(|u|, 1e-6 L): with quadratic convergence a residual at tolerance
// follows an update at about sqrt(tolerance), so this rejects only a residual that is small
// for the wrong reason (a soft direction), at the price of at most one extra iteration.
#include "fem/newton.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace phymul::fem {

namespace {

constexpr double kAbsoluteResidualFloor = 1e-12;  // N
constexpr int kLineSearchHalvings = 12;
constexpr double kArmijo = 1e-4;

std::string number(double v) {
  std::ostringstream out;
  out.precision(6);
  out << v;
  return out.str();
}

}  // namespace

LoadStepper::LoadStepper(System& system, Eigen::VectorXd body, Eigen::VectorXd target,
                         const NodeGeometry& geometry, NewtonSettings settings)
    : system_(system),
      body_(std::move(body)),
      target_(std::move(target)),
      settings_(settings),
      u_(Eigen::VectorXd::Zero(system.dof_count())) {
  system_.evaluate(u_, true);
  if (system_.free_count() > 0) {
    solver_ = std::make_unique<TangentSolver>(system_.free_free(), geometry);
  }
}

Eigen::VectorXd LoadStepper::reaction() const { return system_.internal_force() - s_ * body_; }

Eigen::VectorXd LoadStepper::free_residual_vector(double s) const {
  return system_.gather(system_.internal_force() - s * body_, system_.free_dofs());
}

double LoadStepper::free_residual() const {
  return system_.free_count() > 0 ? free_residual_vector(s_).lpNorm<Eigen::Infinity>() : 0.0;
}

double LoadStepper::threshold(double s) const {
  const Eigen::VectorXd r = system_.internal_force() - s * body_;
  const double reaction = system_.gather(r, system_.prescribed_dofs()).norm();
  const double load = s * body_.norm();
  return std::min(std::max(settings_.tolerance * std::max(reaction, load), kAbsoluteResidualFloor),
                  settings_.force_tolerance);
}

double LoadStepper::update_tolerance() const {
  return std::sqrt(settings_.tolerance) *
         std::max(u_.lpNorm<Eigen::Infinity>(), 1e-6 * settings_.length_scale);
}

bool LoadStepper::factorize(StepFailure& failure) {
  factor_current_ = solver_->factorize(system_.free_free(), failure);
  if (factor_current_) factored_ = system_.tangent_values();  // what a resume refactorises
  return factor_current_;
}

void LoadStepper::save(SolveState& state) const {
  state.newton_iterations = iterations_;
  state.load_factor = s_;
  state.displacement.assign(u_.data(), u_.data() + u_.size());
  state.curvature.assign(curvature_.data(), curvature_.data() + curvature_.size());
  state.curvature_increment = curvature_increment_;
  state.factored_tangent = factor_current_ ? factored_ : std::vector<double>{};
  system_.save_evaluation(state);
}

void LoadStepper::resume(const SolveState& state) {
  if (state.displacement.size() != size_t(u_.size()) ||
      (state.curvature_increment > 0.0 && state.curvature.size() != size_t(u_.size())))
    throw std::invalid_argument("fem: the state to resume from does not fit this problem");
  factor_current_ = false;
  if (!state.factored_tangent.empty() && solver_) {
    StepFailure failure;
    system_.set_tangent_values(state.factored_tangent);  // restore_evaluation sets it back
    if (!factorize(failure))
      throw std::invalid_argument("fem: the saved tangent does not factorise: " + failure.reason);
  }
  system_.restore_evaluation(state);
  iterations_ = state.newton_iterations;
  s_ = state.load_factor;
  u_ = Eigen::Map<const Eigen::VectorXd>(state.displacement.data(), u_.size());
  curvature_increment_ = state.curvature_increment;
  if (curvature_increment_ > 0.0)
    curvature_ = Eigen::Map<const Eigen::VectorXd>(state.curvature.data(), u_.size());
}

// Tangent predictor: the free dofs follow the prescribed increment and the load increment
// through the tangent at the last equilibrium, K_ff du_f = -(r_f(s1) + K_fp du_p), so the
// first iterate is already smooth instead of having all the motion in the boundary layer.
// It reuses the factorisation of the last Newton correction (the tangent at the last iterate,
// one tiny update away from the equilibrium): one factorisation per increment saved. K_fp
// is the current one.
// On top of it goes the part of the previous increment the tangent missed (its second-order
// term), scaled by the squared increment ratio: on the Truth Cube this cuts the predictor's
// residual twentyfold and saves one Newton iteration per load step. If that extrapolated
// state inverts an element, the plain tangent prediction is used.
bool LoadStepper::predict(double s1, StepFailure& failure) {
  const Eigen::VectorXd du_p = (s1 - s_) * system_.gather(target_, system_.prescribed_dofs());
  const Eigen::VectorXd rhs = -(free_residual_vector(s1) + system_.free_prescribed() * du_p);
  if (!factor_current_ && !factorize(failure)) return false;
  system_.scatter_add(solver_->solve(rhs), system_.free_dofs(), u_);
  system_.scatter_add(du_p, system_.prescribed_dofs(), u_);
  predicted_ = u_;
  if (curvature_increment_ > 0.0) {
    const double ratio = (s1 - s_) / curvature_increment_;
    u_ += (ratio * ratio) * curvature_;
    if (u_.allFinite() && system_.evaluate(u_, true)) return true;
    u_ = predicted_;
  }
  if (!u_.allFinite() || !system_.evaluate(u_, true)) {
    failure = {"the predictor inverts an element", false};
    return false;
  }
  return true;
}

// Backtracking on the Euclidean norm of the free residual: the Newton direction is a descent
// direction of |r|^2 even where the tangent is indefinite. A state that already meets the
// residual test (iterating only for the update test) takes the full step, since round-off
// may not decrease further.
bool LoadStepper::line_search(const Eigen::VectorXd& residual, double s1, double& step_norm) {
  const Eigen::VectorXd delta = solver_->solve(-residual);
  const double r0 = residual.norm();
  const bool converged = residual.lpNorm<Eigen::Infinity>() <= threshold(s1);
  Eigen::VectorXd trial = u_;
  double alpha = 1.0;
  for (int k = 0; k <= kLineSearchHalvings; ++k, alpha *= 0.5) {
    trial = u_;
    system_.scatter_add(alpha * delta, system_.free_dofs(), trial);
    if (!trial.allFinite() || !system_.evaluate(trial, true)) continue;
    const Eigen::VectorXd r = free_residual_vector(s1);
    if (converged || r.norm() <= (1.0 - kArmijo * alpha) * r0 ||
        r.lpNorm<Eigen::Infinity>() <= threshold(s1)) {
      u_ = trial;
      step_norm = alpha * delta.lpNorm<Eigen::Infinity>();
      return true;
    }
  }
  system_.evaluate(u_, true);
  return false;
}

void LoadStepper::restore(const Eigen::VectorXd& u, double s) {
  u_ = u;
  s_ = s;
  system_.evaluate(u_, true);
  factor_current_ = false;  // the factorisation belongs to the failed attempt
  curvature_increment_ = 0.0;
}

bool LoadStepper::step_to(double s1, StepFailure& failure) {
  const Eigen::VectorXd start = u_;
  const double s0 = s_;
  if (system_.free_count() == 0) {  // everything prescribed: nothing to solve
    u_ += (s1 - s0) * target_;
    s_ = s1;
    if (system_.evaluate(u_, true)) return true;
    failure = {"the prescribed displacements invert an element", true};
    restore(start, s0);
    return false;
  }
  const auto fail = [&](StepFailure why) {
    failure = std::move(why);
    restore(start, s0);
    return false;
  };
  if (!predict(s1, failure)) return fail(failure);
  double last_update = std::numeric_limits<double>::infinity();
  for (int iteration = 1;; ++iteration) {
    const Eigen::VectorXd r = free_residual_vector(s1);
    const double r_max = r.lpNorm<Eigen::Infinity>();
    if (!std::isfinite(r_max)) return fail({"the residual is not finite", false});
    if (r_max <= threshold(s1) && last_update <= update_tolerance()) break;
    if (iteration > settings_.max_iterations) {
      return fail({"no convergence in " + std::to_string(settings_.max_iterations) +
                       " Newton iterations (free residual " + number(r_max) + " N > " +
                       number(threshold(s1)) + " N)",
                   false});
    }
    if (!factorize(failure)) return fail(failure);
    ++iterations_;
    if (!line_search(r, s1, last_update)) {
      return fail({"the line search found no decrease of the residual (" + number(r_max) +
                       " N) along the Newton direction",
                   false});
    }
  }
  curvature_ = u_ - predicted_;  // what the tangent predictor missed
  curvature_increment_ = s1 - s_;
  s_ = s1;
  return true;
}

}  // namespace phymul::fem
