#include "phymul/simulator.hpp"

#include <fmt/format.h>

#include <cmath>

#include "constraints/constraints.hpp"
#include "constraints/contact.hpp"
#include "forces/forces.hpp"

namespace phymul {
namespace {

// Below this many nodes a thread team costs more than a per-node loop saves.
constexpr int kParallelFrom = 4096;

Vec3 free_axes(const Vec3& inverse_mass) {
  return (inverse_mass.array() > 0.0).cast<double>().matrix();
}

double bounding_diagonal(const std::vector<Vec3>& p) {
  if (p.empty()) return 1.0;
  Vec3 lo = p[0], hi = p[0];
  for (const Vec3& q : p) lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
  return std::max((hi - lo).norm(), 1e-12);
}

int component_of(const Model& model, int node) {
  for (int c = 0; c < int(model.components.size()); ++c) {
    const Component& k = model.components[c];
    if (node >= k.first_node && node < k.first_node + k.node_count) return c;
  }
  return -1;
}

}  // namespace

Simulator::Simulator(Model model) : model_(std::move(model)) {
  if (model_.inverse_mass.size() != model_.rest_position.size()) finalize(model_);
  state_ = make_state(model_);
  const size_t n = model_.rest_position.size();
  x_start_.assign(n, Vec3::Zero());
  if (model_.settings.integrator == Integrator::newton_cotes) {  // only it needs them
    v_start_.assign(n, Vec3::Zero());
    a1_.assign(n, Vec3::Zero());
  }
  f_start_.assign(n, Vec3::Zero());
  scratch_.assign(n, Vec3::Zero());
  size_scale_ = bounding_diagonal(model_.rest_position);
  inertia_ = model_.mass;
  if (model_.settings.mode == SolveMode::static_equilibrium &&
      model_.settings.relaxation_mass_scaling)
    scale_masses_for_relaxation();
  const double stable = stable_time_step(model_);
  dt_ = model_.settings.dt ? *model_.settings.dt : model_.settings.dt_safety * stable;
  if (!std::isfinite(dt_)) dt_ = 1e-3;  // no stiffness at all: any step is stable
  apply_position_constraints(model_, state_.x, 0.0, scratch_);
  compute_forces(model_, state_, 0.0);
}

// Static equilibrium does not depend on the masses; the time to reach it by pseudo-dynamics
// does. Lumped masses make corner and edge nodes 8 and 4 times lighter than interior ones
// while their stiffness is about the same: they alone set the stable step. Masses
// proportional to each node's stiffness row give every node the largest frequency, so the
// step stays and the slow modes speed up (Underwood's dynamic relaxation). Gravity keeps
// the true masses (Model::mass).
void Simulator::scale_masses_for_relaxation() {
  const std::vector<double> row = stiffness_row_sums(model_);
  double omega2 = 0.0;
  for (int i = 0; i < model_.node_count(); ++i) omega2 = std::max(omega2, row[i] / inertia_[i]);
  if (omega2 == 0.0) return;
  for (int i = 0; i < model_.node_count(); ++i) {
    if (row[i] == 0.0) continue;  // no stiffness: keeps its mass
    inertia_[i] = row[i] / omega2;
    for (int a = 0; a < 3; ++a)
      if (model_.inverse_mass[i][a] != 0.0) model_.inverse_mass[i][a] = 1.0 / inertia_[i];
  }
}

void Simulator::step() {
  const double load_time = state_.time + dt_;
  if (model_.settings.integrator == Integrator::verlet)
    step_verlet(dt_, load_time);
  else
    step_newton_cotes(dt_, load_time);
  state_.time = load_time;
  ++state_.step;
  check_stability();
}

// Velocity Verlet; the constraint projection enters the half-step velocity as the
// correction over dt (the reaction of the constraint).
void Simulator::step_verlet(double h, double load_time) {
  State& s = state_;
  std::vector<Vec3>& a = f_start_;  // accelerations, tangent to the volume constraints
  accelerations(a);
  const int n = model_.node_count();
#pragma omp parallel for schedule(static) if (n >= kParallelFrom)
  for (int i = 0; i < n; ++i) {
    x_start_[i] = s.x[i];
    s.x[i] += h * (s.v[i] + 0.5 * h * a[i]);
  }
  apply_position_constraints(model_, s.x, load_time, scratch_);
#pragma omp parallel for schedule(static) if (n >= kParallelFrom)
  for (int i = 0; i < n; ++i) s.v[i] = (s.x[i] - x_start_[i]) / h;
  compute_forces(model_, s, load_time);
  load_time_ = load_time;
  // The velocity projection below is linear: projecting the sum makes the kick tangent too.
  accelerations(a, /*tangent=*/false);
#pragma omp parallel for schedule(static) if (n >= kParallelFrom)
  for (int i = 0; i < n; ++i) s.v[i] += 0.5 * h * a[i];
  project_volume_velocities(model_, s.x, s.v, scratch_);
}

// Without their part along the volume gradients (the pressure the projection would undo
// anyway), accelerations keep the drift on the constraint: the projection then corrects only
// second-order terms, and relaxation converges instead of stalling on that round trip.
void Simulator::accelerations(std::vector<Vec3>& a, bool tangent) {
  const double c = model_.damping;
  const int n = model_.node_count();
#pragma omp parallel for schedule(static) if (n >= kParallelFrom)
  for (int i = 0; i < n; ++i)
    a[i] = model_.inverse_mass[i].cwiseProduct(state_.f[i]) -
           c * state_.v[i].cwiseProduct(free_axes(model_.inverse_mass[i]));
  if (tangent) project_volume_velocities(model_, state_.x, a, scratch_);
}

// The paper's Newton-Cotes family: an Euler predictor, then the trapezoid rule on the
// accelerations at both ends (second order).
void Simulator::step_newton_cotes(double h, double load_time) {
  State& s = state_;
  const int n = model_.node_count();
  std::vector<Vec3>& a0 = f_start_;
  accelerations(a0);
  for (int i = 0; i < n; ++i) {
    x_start_[i] = s.x[i];
    v_start_[i] = s.v[i];
    s.x[i] += h * s.v[i];
    s.v[i] += h * a0[i];
  }
  apply_prescribed(model_, s.x, load_time);
  compute_forces(model_, s, load_time);
  accelerations(a1_);
  for (int i = 0; i < n; ++i) {
    s.v[i] = v_start_[i] + 0.5 * h * (a0[i] + a1_[i]);
    s.x[i] = x_start_[i] + 0.5 * h * (v_start_[i] + s.v[i]);
    a1_[i] = s.x[i];  // spent: keep the unconstrained position instead
  }
  apply_position_constraints(model_, s.x, load_time, scratch_);
  for (int i = 0; i < n; ++i) s.v[i] += (s.x[i] - a1_[i]) / h;
  project_volume_velocities(model_, s.x, s.v, scratch_);
  compute_forces(model_, s, load_time);
  load_time_ = load_time;
}

void Simulator::check_stability() const {
  const State& s = state_;
  const int n = model_.node_count();
  bool all_well = true;  // a parallel look first; the first bad node is then found in order
#pragma omp parallel for schedule(static) if (n >= kParallelFrom) reduction(&& : all_well)
  for (int i = 0; i < n; ++i) {
    const double moved = (s.x[i] - model_.rest_position[i]).norm();
    all_well =
        all_well && std::isfinite(moved) && s.v[i].allFinite() && moved <= 10.0 * size_scale_;
  }
  if (all_well) return;
  for (int i = 0; i < n; ++i) {
    const double moved = (s.x[i] - model_.rest_position[i]).norm();
    const bool finite = std::isfinite(moved) && s.v[i].allFinite();
    if (finite && moved <= 10.0 * size_scale_) continue;
    const int c = component_of(model_, i);
    const std::string what =
        finite ? fmt::format("moved {:.3g} m, more than 10 times the model's size ({:.3g} m)",
                             moved, size_scale_)
               : std::string("has a non-finite position or velocity");
    throw InstabilityError(
        fmt::format("the simulation became unstable at t = {:.6g} s (step {}): node {} of "
                    "component '{}' {}. The time step is {:.3g} s and the stability estimate "
                    "is {:.3g} s: set simulation.dt smaller (or 'auto' with dt_safety below "
                    "0.5), add damping, or check the stiffness and masses.",
                    s.time, s.step, i, c >= 0 ? model_.components[c].name : "?", what, dt_,
                    stable_time_step(model_)),
        i, s.time);
  }
}

double Simulator::kinetic_energy() const {
  double e = 0.0;
  for (int i = 0; i < model_.node_count(); ++i) e += 0.5 * inertia_[i] * state_.v[i].squaredNorm();
  return e;
}

double Simulator::max_residual_force() {
  // f_start_ holds the residual and scratch_ the volume gradients: both free between steps.
  std::vector<Vec3>& r = f_start_;
  for (int i = 0; i < model_.node_count(); ++i)
    r[i] = state_.f[i].cwiseProduct(free_axes(model_.inverse_mass[i]));
  for (const VolumeConstraint& c : model_.volumes) {
    volume_gradient(c, state_.x, scratch_);
    double rg = 0.0, gg = 0.0;
    for (int i : c.nodes) {
      scratch_[i] = scratch_[i].cwiseProduct(free_axes(model_.inverse_mass[i]));
      rg += r[i].dot(scratch_[i]);
      gg += scratch_[i].squaredNorm();
    }
    if (gg == 0.0) continue;
    const double pressure = rg / gg;  // the part of the force the constraint balances
    for (int i : c.nodes) r[i] -= pressure * scratch_[i];
  }
  remove_contact_forces(r);
  double largest = 0.0;
  for (int i = 0; i < model_.node_count(); ++i) largest = std::max(largest, r[i].norm());
  return largest;
}

// A node touching an obstacle can be pushed into it with any force: that part of its
// residual is the contact's reaction, not an imbalance.
void Simulator::remove_contact_forces(std::vector<Vec3>& r) const {
  constexpr double kTouching = 1e-12;  // m, as obstacle_force counts contact
  auto remove = [&](const RigidObstacle& o, int i) {
    const SurfaceDistance d = obstacle_distance(o, state_.x[i], load_time_);
    if (std::abs(d.distance) > kTouching) return;
    const Vec3 push = o.keep_inside ? Vec3(-d.normal) : d.normal;  // how the obstacle can push
    const double into = r[i].dot(push);
    if (into < 0.0) r[i] -= into * push;
  };
  for (const RigidObstacle& o : model_.obstacles) {
    if (o.nodes.empty())
      for (int i = 0; i < model_.node_count(); ++i) remove(o, i);
    else
      for (int i : o.nodes) remove(o, i);
  }
}

std::vector<Vec3> Simulator::support_reactions() const {
  // Each volume constraint carries a pressure: the least-squares multiplier of its gradient
  // against the forces on the free axes (what max_residual_force takes out).
  std::vector<Vec3> reaction(state_.f);
  std::vector<Vec3> grad(state_.x.size(), Vec3::Zero());
  for (const VolumeConstraint& c : model_.volumes) {
    volume_gradient(c, state_.x, grad);
    double fg = 0.0, gg = 0.0;
    for (int i : c.nodes) {
      const Vec3 free_grad = grad[i].cwiseProduct(free_axes(model_.inverse_mass[i]));
      fg += state_.f[i].dot(free_grad);
      gg += free_grad.squaredNorm();
    }
    if (gg == 0.0) continue;
    for (int i : c.nodes) reaction[i] -= (fg / gg) * grad[i];
  }
  for (int i = 0; i < model_.node_count(); ++i) {
    const Vec3 held = Vec3::Ones() - free_axes(model_.inverse_mass[i]);
    reaction[i] = -reaction[i].cwiseProduct(held);
  }
  return reaction;
}

std::vector<double> Simulator::component_volumes() const {
  std::vector<double> v;
  for (const Component& c : model_.components)
    v.push_back(c.boundary.empty() ? std::nan("") : enclosed_volume(state_.x, c.boundary));
  return v;
}

StaticResult Simulator::relax(double load_time, long max_iterations,
                              const std::function<void(long, double)>& progress, double tolerance) {
  StaticResult result;
  apply_position_constraints(model_, state_.x, load_time, scratch_);
  compute_forces(model_, state_, load_time);
  load_time_ = load_time;
  double previous_kinetic = 0.0;
  Fire fire;
  for (;;) {
    result.residual = max_residual_force();
    if (result.residual < tolerance) {
      result.converged = true;
      break;
    }
    if (result.iterations >= max_iterations) break;
    if (model_.settings.integrator == Integrator::verlet)
      step_verlet(dt_, load_time);
    else
      step_newton_cotes(dt_, load_time);
    ++result.iterations;
    ++state_.step;
    check_stability();
    if (model_.settings.relaxation == Relaxation::fire) {
      fire_update(fire);
    } else if (model_.settings.relaxation == Relaxation::kinetic) {
      // Dynamic relaxation: at a kinetic-energy peak the system is nearest its minimum
      // along the current motion, so restart from rest there.
      const double kinetic = kinetic_energy();
      if (kinetic < previous_kinetic) {
        for (Vec3& v : state_.v) v.setZero();
        previous_kinetic = 0.0;
      } else {
        previous_kinetic = kinetic;
      }
    }
    if (progress && result.iterations % 256 == 0) progress(result.iterations, result.residual);
  }
  state_.time = load_time;
  return result;
}

// FIRE (Bitzek et al. 2006) at the scene's dt: while the motion goes downhill (power
// P = f.v > 0) the velocity is turned towards the force, v <- (1 - alpha) v + alpha |v| f/|f|
// in the mass metric, alpha shrinking after five downhill steps; uphill it restarts from
// rest. The force is the tangent one (volume pressure removed), as the motion's. On the
// Truth Cube compression it takes 315 iterations at 8^3 and 781 at 16^3 where kinetic
// damping took 430 and 1,391.
void Simulator::fire_update(Fire& fire) {
  std::vector<Vec3>& a = f_start_;  // free between steps
  accelerations(a);
  remove_contact_forces(a);  // what pushes into an obstacle is not downhill
  const int n = model_.node_count();
  double power = 0.0, vv = 0.0, aa = 0.0;
  for (int i = 0; i < n; ++i) {
    power += inertia_[i] * a[i].dot(state_.v[i]);
    vv += inertia_[i] * state_.v[i].squaredNorm();
    aa += inertia_[i] * a[i].squaredNorm();
  }
  if (!(power > 0.0)) {
    for (Vec3& v : state_.v) v.setZero();
    fire = Fire{};
    return;
  }
  const double keep = 1.0 - fire.alpha, turn = aa > 0.0 ? fire.alpha * std::sqrt(vv / aa) : 0.0;
#pragma omp parallel for schedule(static) if (n >= kParallelFrom)
  for (int i = 0; i < n; ++i) state_.v[i] = keep * state_.v[i] + turn * a[i];
  if (++fire.downhill > 5) fire.alpha *= 0.99;
}

StaticResult Simulator::solve_static(const std::function<void(long, double)>& progress) {
  constexpr double kIntermediate = 1000.0;
  const SimulationSpec& s = model_.settings;
  StaticResult total;
  for (int k = 1; k <= s.load_steps; ++k) {
    const double load_time = s.duration * double(k) / double(s.load_steps);
    // Intermediate equilibria only guide the path: loosely relaxed, they serve as well.
    const double tolerance = k < s.load_steps ? kIntermediate * s.tolerance : s.tolerance;
    const StaticResult r =
        relax(load_time, s.max_iterations - total.iterations, progress, tolerance);
    total.iterations += r.iterations;
    total.residual = r.residual;
    total.converged = r.converged;
    if (!r.converged) break;
  }
  return total;
}

}  // namespace phymul
