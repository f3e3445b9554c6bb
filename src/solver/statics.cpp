// Static equilibrium by pseudo-dynamics (kinetic damping, FIRE or viscous), load step by load
// step, and what equilibria are measured by: residual forces, support reactions, volumes.
#include <algorithm>
#include <cmath>

#include "constraints/constraints.hpp"
#include "constraints/contact.hpp"
#include "constraints/coupled_volume.hpp"
#include "constraints/deformable_contact.hpp"
#include "constraints/doubled.hpp"
#include "model/thread_team.hpp"
#include "model/workspace.hpp"
#include "phymul/simulation.hpp"
#include "solver/implicit_step.hpp"
#include "solver/rigid.hpp"
#include "solver/step.hpp"

namespace phymul {
namespace {

constexpr int kParallelFrom = 4096;  // nodes; below, a thread team costs more than it saves
constexpr double kTouching = 1e-12;  // m: a node this close touches an obstacle

Vec3 free_axes(const Vec3& inverse_mass) {
  return (inverse_mass.array() > 0.0).cast<double>().matrix();
}

// Takes out of r the part each volume constraint balances: its pressure, the least-squares
// multiplier of its gradient against r on the free axes. Removed along the free part of the
// gradient (residual) or the whole gradient (support reactions, which then carry the held
// part). Surfaces sharing nodes: Gauss-Seidel sweeps until what is left to take out is far
// below the tolerance (one pass is exact for disjoint ones).
void remove_volume_pressures(const Model& model, Workspace& work, std::span<const Vec3> x,
                             std::vector<Vec3>& r, std::vector<Vec3>& grad, bool on_free_axes,
                             std::span<const ObstacleContact> contact = {}) {
  if (model.coupled_volumes &&
      remove_coupled_volume_pressures(model, work, x, r, grad, on_free_axes, contact))
    return;  // all pressures at once
  const int sweeps = model.coupled_volumes ? 200 : 1;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    double largest_change = 0.0;
    for (const VolumeConstraint& c : model.volumes) {
      volume_gradient(c, x, grad);
      double rg = 0.0, gg = 0.0, longest = 0.0;
      for (int i : c.nodes) {
        const Vec3 free_grad = grad[i].cwiseProduct(free_axes(model.inverse_mass[i]));
        if (on_free_axes) grad[i] = free_grad;
        rg += r[i].dot(free_grad);
        gg += free_grad.squaredNorm();
        longest = std::max(longest, grad[i].norm());
      }
      // Against an obstacle a node's push along the contact normal is the contact's to
      // balance, whatever its size: only its tangential part tells the pressure.
      for (const auto& [i, n, friction] : contact) {
        const Vec3 free_grad = grad[i].cwiseProduct(free_axes(model.inverse_mass[i]));
        rg -= r[i].dot(n) * free_grad.dot(n);
        gg -= free_grad.dot(n) * free_grad.dot(n);
      }
      if (gg == 0.0) continue;
      const double pressure = rg / gg;
      for (int i : c.nodes) r[i] -= pressure * grad[i];
      largest_change = std::max(largest_change, std::abs(pressure) * longest);
    }
    if (largest_change <= 1e-3 * model.settings.tolerance) break;
  }
}

// The nodes touching obstacle k at `time`, appended to `contacts`: on its surface, or put on
// it by the last step's contact stage (the volume projection after it may have moved the node
// off by a hair).
void add_touching_nodes(const Model& model, const Data& d, int k, double time,
                        std::vector<ObstacleContact>& contacts) {
  const RigidObstacle& o = model.obstacles.at(size_t(k));  // obstacle_force takes any index
  // The obstacle where the controls put it: its own motion unless a program moved it.
  const Schedule& motion = d.controls.obstacle_motion[size_t(k)];
  auto add = [&](int i) {
    const SurfaceDistance distance = obstacle_distance(o, motion, d.x[size_t(i)], time);
    const bool moved = !d.obstacle_touching.empty() && d.obstacle_touching[size_t(i)] == k;
    if (std::abs(distance.distance) > kTouching && !moved) return;
    contacts.push_back({i, o.keep_inside ? Vec3(-distance.normal) : distance.normal, o.friction});
  };
  if (o.nodes.empty())
    for (int i = 0; i < model.node_count(); ++i) add(i);
  else
    for (int i : o.nodes) add(i);
}

void find_obstacle_contacts(const Model& model, Data& d) {
  d.work->contacts.clear();
  for (int k = 0; k < int(model.obstacles.size()); ++k)
    add_touching_nodes(model, d, k, d.load_time, d.work->contacts);
}

// A node touching an obstacle can be pushed into it with any force: that part of its
// residual is the contact's reaction, not an imbalance.
void remove_contact_forces(std::span<const ObstacleContact> contacts, std::vector<Vec3>& r) {
  for (const auto& [i, push, friction] : contacts) {
    const double into = r[i].dot(push);
    if (into >= 0.0) continue;
    r[i] -= into * push;
    // Friction holds a tangential force up to mu times the normal one.
    const double tangential = r[i].norm(), bound = -friction * into;
    if (tangential > 0.0) r[i] *= tangential <= bound ? 0.0 : (tangential - bound) / tangential;
  }
}

// FIRE (Bitzek et al. 2006) at the scene's dt: while the motion goes downhill (power
// P = f.v > 0) the velocity is turned towards the force, v <- (1 - alpha) v + alpha |v| f/|f|
// in the mass metric, alpha shrinking after five downhill steps; uphill it restarts from
// rest. The force is the tangent one (volume pressure removed), as the motion's. On the
// Truth Cube compression it takes 303 iterations at 8^3 and 759 at 16^3 where kinetic
// damping took 430 and 1,391.
void fire_update(const Model& model, Data& d, StaticProgress& fire) {
  Workspace& work = *d.work;
  std::vector<Vec3>&a = work.f_start, &volume_scratch = work.x_start;  // free between steps
  accelerations(model, d, a, volume_scratch);
  find_obstacle_contacts(model, d);
  remove_contact_forces(work.contacts, a);  // what pushes into an obstacle is not downhill
  const int n = model.node_count();
  const std::vector<double>& inertia = model.inertia;
  double power = 0.0, vv = 0.0, aa = 0.0;
  for (int i = 0; i < n; ++i) {
    power += inertia[i] * a[i].dot(d.v[i]);
    vv += inertia[i] * d.v[i].squaredNorm();
    aa += inertia[i] * a[i].squaredNorm();
  }
  if (!(power > 0.0)) {
    for (Vec3& v : d.v) v.setZero();
    stop_rigid_bodies(d);
    fire.fire_alpha = StaticProgress{}.fire_alpha;
    fire.fire_downhill = 0;
    return;
  }
  const double alpha = fire.fire_alpha;
  const double keep = 1.0 - alpha, turn = aa > 0.0 ? alpha * std::sqrt(vv / aa) : 0.0;
  for_each_index(n, team_pays(n, kParallelFrom),
                 [&](int i) { d.v[i] = keep * d.v[i] + turn * a[i]; });
  if (++fire.fire_downhill > 5) fire.fire_alpha *= 0.99;
}

// The implicit static solver: a backward-Euler step of 1000 times dt from rest (its
// inertia a weak pull towards where the step started, which keeps the iteration matrix
// definite where nothing holds a body), solved to the static tolerance or 20 solves. Its fixed
// point, a step that does not move, is the equilibrium f = 0.
void implicit_static_step(const Model& model, Data& d, double load_time, double tolerance) {
  for (Vec3& v : d.v) v.setZero();
  stop_rigid_bodies(d);
  step_implicit(model, d, 1000.0 * d.dt, load_time, model.settings.implicit_iterations, tolerance);
  for (Vec3& v : d.v) v.setZero();
  stop_rigid_bodies(d);
}

StaticResult continue_relax(const Model& model, Data& d, double load_time, long max_iterations,
                            const RelaxProgress& progress, double tolerance) {
  StaticProgress& p = d.static_progress;
  StaticResult result;
  for (;;) {
    result.residual = max_residual_force(model, d);
    if (result.residual < tolerance) {
      result.converged = true;
      break;
    }
    if (p.step_iterations >= max_iterations) break;
    // (Relaxation is explicit pseudo-dynamics: the implicit integrator relaxes by Verlet.)
    if (model.settings.solver == StaticSolver::implicit)
      implicit_static_step(model, d, load_time, tolerance);
    else if (model.settings.integrator == Integrator::newton_cotes)
      step_newton_cotes(model, d, d.dt, load_time);
    else
      step_verlet(model, d, d.dt, load_time);
    ++p.step_iterations;
    ++d.step;
    checked_step(model, d, d.time, load_time);
    if (model.settings.solver == StaticSolver::implicit) {
      // Each step starts from rest: the velocities only told the step's motion.
    } else if (model.settings.relaxation == Relaxation::fire) {
      fire_update(model, d, p);
    } else if (model.settings.relaxation == Relaxation::kinetic) {
      // Dynamic relaxation: at a kinetic-energy peak the system is nearest its minimum
      // along the current motion, so restart from rest there.
      const double kinetic = kinetic_energy(model, d);
      if (kinetic < p.previous_kinetic) {
        for (Vec3& v : d.v) v.setZero();
        stop_rigid_bodies(d);
        p.previous_kinetic = 0.0;
      } else {
        p.previous_kinetic = kinetic;
      }
    }
    if (progress && p.step_iterations % 256 == 0) progress(p.step_iterations, result.residual);
  }
  result.iterations = p.step_iterations;
  d.time = load_time;
  return result;
}

// The load steps from d.static_progress on: the one under way continues where it stopped.
StaticResult static_load_steps(const Model& model, Data& d, const RelaxProgress& progress) {
  // Intermediate equilibria only guide the path: loosely relaxed, they serve as well.
  constexpr double kIntermediate = 1000.0;
  const SimulationSpec& s = model.settings;
  StaticProgress& p = d.static_progress;
  StaticResult total;
  const bool resuming = p.load_step > 0;
  if (!resuming) p.load_step = 1;
  for (bool first = true; p.load_step <= s.load_steps; ++p.load_step, first = false) {
    const double load_time = s.duration * double(p.load_step) / double(s.load_steps);
    const long budget = s.max_iterations - p.iterations;
    const double tolerance = p.load_step < s.load_steps ? kIntermediate * s.tolerance : s.tolerance;
    const StaticResult r = resuming && first
                               ? continue_relax(model, d, load_time, budget, progress, tolerance)
                               : relax(model, d, load_time, budget, progress, tolerance);
    p.iterations += r.iterations;
    p.step_iterations = 0;
    total.iterations = p.iterations;
    total.residual = r.residual;
    total.converged = r.converged;
    if (!r.converged) break;
    // Between load steps too: a run can stop (and checkpoint) there even when no load step
    // needs 256 iterations.
    if (progress && p.load_step < s.load_steps) progress(r.iterations, r.residual);
  }
  return total;
}

}  // namespace

double kinetic_energy(const Model& model, const Data& d) {
  double e = 0.0;
  const std::vector<double>& inertia = model.inertia;
  for (int i = 0; i < model.node_count(); ++i) e += 0.5 * inertia[i] * d.v[i].squaredNorm();
  return e;
}

double max_residual_force(const Model& model, Data& d) {
  Workspace& work = *d.work;
  // f_start holds the residual and x_start the volume gradients: both free between steps.
  std::vector<Vec3>& r = work.f_start;
  std::copy(d.f.begin(), d.f.end(), r.begin());
  // The contact pairs' forces are known (the last step's): with them in, the volumes'
  // pressures are fitted to what they balance, not biased by a contact on their surface.
  add_deformable_contact_forces(d.pair_contacts, d.dt, r);
  for (int i = 0; i < model.node_count(); ++i)
    r[i] = r[i].cwiseProduct(free_axes(model.inverse_mass[i]));
  gather_doubled(model, r);
  find_obstacle_contacts(model, d);
  remove_volume_pressures(model, work, d.x, r, work.x_start, /*on_free_axes=*/true, work.contacts);
  remove_contact_forces(work.contacts, r);
  double largest = 0.0;
  for (int i = 0; i < model.node_count(); ++i) largest = std::max(largest, r[i].norm());
  return std::max(largest, rigid_residual(model, d));
}

std::vector<Vec3> support_reactions(const Model& model, const Data& d) {
  // Each volume constraint carries a pressure: the least-squares multiplier of its gradient
  // against the forces on the free axes (what max_residual_force takes out). Its scratch is
  // a copy of the workspace, so that the data stays as it is.
  // The contact normals are left to the contacts, as there: an obstacle's push would
  // otherwise bias the pressures, and with them every held node's reaction.
  Workspace work = *d.work;
  work.contacts.clear();
  for (int k = 0; k < int(model.obstacles.size()); ++k)
    add_touching_nodes(model, d, k, d.time, work.contacts);
  std::vector<Vec3> reaction(d.f);
  add_deformable_contact_forces(d.pair_contacts, d.dt, reaction);  // known, as in the residual
  std::vector<Vec3> grad(d.x.size(), Vec3::Zero());
  remove_volume_pressures(model, work, d.x, reaction, grad, /*on_free_axes=*/false, work.contacts);
  for (int i = 0; i < model.node_count(); ++i) {
    const Vec3 held = Vec3::Ones() - free_axes(model.inverse_mass[i]);
    reaction[i] = -reaction[i].cwiseProduct(held);
  }
  // A spring support holds its nodes with its springs' pull.
  for (const SpringSupport& springs : model.springs)
    for (int i : springs.nodes)
      reaction[size_t(i)] -= springs.stiffness * (d.x[size_t(i)] - model.rest_position[size_t(i)]);
  // A free rigid body is held by nothing: its nodes' forces move it.
  for (const RigidBody& body : model.rigid_bodies)
    if (!body.driven)
      for (int i : body.nodes) reaction[i].setZero();
  return reaction;
}

Vec3 obstacle_force(const Model& model, const Data& d, int obstacle) {
  // The residual's own accounting on a copy of the scratch: each volume's pressure out (the
  // contact normals left to the contacts), so that what is left on a touching node is minus
  // the contact's force.
  Workspace work = *d.work;
  work.contacts.clear();
  add_touching_nodes(model, d, obstacle, d.time, work.contacts);
  std::vector<Vec3> r(d.f.size()), grad(d.x.size(), Vec3::Zero());
  r = d.f;
  add_deformable_contact_forces(d.pair_contacts, d.dt, r);  // known, as in the residual
  for (int i = 0; i < model.node_count(); ++i)
    r[size_t(i)] = r[size_t(i)].cwiseProduct(free_axes(model.inverse_mass[size_t(i)]));
  remove_volume_pressures(model, work, d.x, r, grad, /*on_free_axes=*/true, work.contacts);
  Vec3 force = Vec3::Zero();
  for (const ObstacleContact& c : work.contacts) force -= r[size_t(c.node)];
  return force;
}

std::vector<double> component_volumes(const Model& model, const Data& d) {
  std::vector<double> v;
  for (const Component& c : model.components)
    v.push_back(c.boundary.empty() ? std::nan("") : enclosed_volume(d.x, c.boundary));
  return v;
}

StaticResult relax(const Model& model, Data& d, double load_time, long max_iterations,
                   const RelaxProgress& progress, double tolerance) {
  if (!finalized(model)) throw_not_finalized();
  d.static_progress.step_iterations = 0;
  d.static_progress.previous_kinetic = 0.0;
  d.static_progress.fire_alpha = StaticProgress{}.fire_alpha;
  d.static_progress.fire_downhill = 0;
  drift_rigid_bodies(model, d, 0.0, load_time);  // driven bodies at their new pose
  apply_position_constraints(model, d.controls, *d.work, d.x, load_time,
                             d.work->f_start);  // free between steps
  compute_forces(model, d, load_time);
  d.load_time = load_time;
  return continue_relax(model, d, load_time, max_iterations, progress, tolerance);
}

StaticResult solve_static(const Model& model, Data& d, const RelaxProgress& progress) {
  d.static_progress = StaticProgress{};
  return static_load_steps(model, d, progress);
}

StaticResult resume_static(const Model& model, Data& d, const RelaxProgress& progress) {
  return static_load_steps(model, d, progress);
}

}  // namespace phymul
