// Stepping a model: explicit dynamics (DESIGN 2.3) and static relaxation to equilibrium.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "phymul/model.hpp"

namespace phymul {
struct DeformableContactWorkspace;
}

namespace phymul {

// A run that became unstable: names the node, component and time, and what to change.
class InstabilityError : public std::runtime_error {
 public:
  InstabilityError(const std::string& message, int node, double time)
      : std::runtime_error(message), node(node), time(time) {}
  int node;
  double time;
};

// Largest stable time step (s) of the explicit schemes for this model, from a Gershgorin
// bound on the shape-memory stiffness over the node masses (undamped central difference
// limit 2/omega_max).
double stable_time_step(const Model& model);
// The same with these node inertias (kg) in place of the masses (mass scaling).
double stable_time_step(const Model& model, const std::vector<double>& inertia);
// Per node, the Gershgorin row sum (N/m) of the shape-memory stiffness behind that bound.
std::vector<double> stiffness_row_sums(const Model& model);

// Largest stable step (s) of central differences for the highest angular frequency omega
// (rad/s) under mass-proportional damping (1/s); infinity when omega is zero.
double verlet_stable_step(double omega, double damping);

// The highest angular frequency of the forces linearised at `state`, over these inertias
// (kg per node), on the free axes (simulation.dt_estimate: power). omega^2 lies between
// `rayleigh` and `rayleigh + residual` once the iteration has found the top eigenvector (the
// residual bounds the distance to an eigenvalue); omega() takes the top, the safe side.
struct FrequencyEstimate {
  double rayleigh = 0.0;  // (rad/s)^2, Rayleigh quotient of the last iterate
  double residual = 0.0;  // (rad/s)^2, |A y - rayleigh y| for the unit iterate y
  int iterations = 0;
  double omega() const { return std::sqrt(std::max(rayleigh + residual, 0.0)); }
};
// Power iteration, the force Jacobian by central differences of the force routine; stops
// when the residual is below 1e-4 of the quotient or after max_iterations (two force passes
// each). Allocates: for set-up, not inside a step.
FrequencyEstimate highest_frequency(const Model& model, const State& state,
                                    const std::vector<double>& inertia, double load_time = 0.0,
                                    int max_iterations = 400);

struct StaticResult {
  bool converged = false;
  long iterations = 0;    // steps of pseudo-dynamics, all load steps together
  double residual = 0.0;  // N, largest free residual force at the end
};

// Where a static solve stands between two relaxation iterations: with State and the load
// time, all that its next iteration reads (a checkpoint resumes from it).
struct StaticProgress {
  int load_step = 0;              // the load step under way, 1-based; 0 before the first
  long iterations = 0;            // in the load steps before it
  long step_iterations = 0;       // in the load step under way
  double previous_kinetic = 0.0;  // J, the kinetic damping's last peak candidate
  double fire_alpha = 0.1;        // FIRE: share of the force direction mixed into velocities
  long fire_downhill = 0;         // FIRE: steps since its last restart
};

class Simulator {
 public:
  explicit Simulator(Model model);

  const Model& model() const { return model_; }
  const State& state() const { return state_; }
  State& state() { return state_; }
  double dt() const { return dt_; }
  // s: the stability estimate dt: auto takes its share of (after any mass scaling).
  double stable_dt() const { return stable_dt_; }
  void set_dt(double dt) { dt_ = dt; }  // s

  // One explicit step of dt with the scene's integrator; loads at the new time. An unstable
  // step throws InstabilityError and leaves the state as it was before it.
  void step();
  // Relax to equilibrium with the loads of load_time (s); stops when the largest free
  // residual force is below the scene's tolerance or after max_iterations.
  StaticResult relax(double load_time, long max_iterations,
                     const std::function<void(long, double)>& progress, double tolerance);
  StaticResult relax(double load_time, long max_iterations,
                     const std::function<void(long, double)>& progress = {}) {
    return relax(load_time, max_iterations, progress, model_.settings.tolerance);
  }
  // The scene's static mode: load steps up to the scene's duration.
  StaticResult solve_static(const std::function<void(long, double)>& progress = {});
  // Continues a static solve from static_progress() (set by restore), as if never stopped.
  StaticResult resume_static(const std::function<void(long, double)>& progress = {});

  // Checkpoints: what the next step reads besides State, and putting it all back.
  double load_time() const { return load_time_; }
  const StaticProgress& static_progress() const { return static_progress_; }
  // The state must fit the model (every array at make_state's size): std::invalid_argument
  // naming the member otherwise.
  void restore(const State& state, double load_time, const StaticProgress& progress);

  double kinetic_energy() const;  // J
  // kg: the inertia mass scaling (simulation.mass_scaling_dt) or the static relaxation's
  // fictitious masses add to the true masses, summed over the nodes.
  double added_inertia() const;
  // kg per node: the inertia the steps use (the masses unless scaled, above).
  const std::vector<double>& inertia() const { return inertia_.empty() ? model_.mass : inertia_; }
  // Largest nodal force (N) on the free axes, less the part a volume constraint balances.
  double max_residual_force();
  // Force (N) each position constraint exerts on its node, on the held axes (zero on free
  // ones): minus the forces there, the pressure of the volume constraints included. At
  // equilibrium they balance every load. Allocates: not for inside a step.
  std::vector<Vec3> support_reactions() const;
  // Enclosed volume (m^3) of every component with a closed boundary, in component order
  // (NaN for the others).
  std::vector<double> component_volumes() const;

 private:
  void step_verlet(double dt, double load_time);
  void step_newton_cotes(double dt, double load_time);
  void check_stability() const;
  InstabilityError non_finite_energy() const;  // which cell, if a finite element inverted
  // check_stability; when it fails, the state goes back to before the step, then it throws.
  void checked_step(double time, double previous_load);
  StaticResult continue_relax(double load_time, long max_iterations,
                              const std::function<void(long, double)>& progress, double tolerance);
  StaticResult static_load_steps(const std::function<void(long, double)>& progress);
  // Tangent to the volume constraints unless volume_scratch (their gradients, node count) is
  // empty.
  void accelerations(std::vector<Vec3>& a, std::span<Vec3> volume_scratch);
  void drift(double h);
  void half_kick_from_positions(double h);
  void find_obstacle_contacts();  // fills contacts_ at the current positions
  // Takes out of r what the obstacles in contacts_ can balance (call find_obstacle_contacts).
  void remove_contact_forces(std::vector<Vec3>& r) const;
  // contact: nodes against an obstacle and its normal there, whose normal push is not
  // evidence of a pressure.
  void remove_volume_pressures(std::vector<Vec3>& r, std::vector<Vec3>& grad, bool on_free_axes,
                               std::span<const ObstacleContact> contact = {}) const;
  struct ContactStep begin_contact_step(double dt);
  void end_contact_step(double dt);
  void scale_masses_for_relaxation();
  void scale_masses_to(double target);  // s: mass scaling, dynamics
  void give_inertia(int i, double inertia);
  void fire_update(StaticProgress& fire);
  static void release_free_memory();

  Model model_;
  State state_;
  double dt_ = 0.0;
  double stable_dt_ = 0.0;
  double load_time_ = 0.0;  // time at which State::f was evaluated
  StaticProgress static_progress_;
  // Sized once: no allocation in a step. Memory is the limit on large models (README), so
  // node-sized buffers double up where their lives do not overlap: the volume gradients go
  // to f_start_ (the accelerations) once spent, or to x_start_ before it is filled and
  // between steps. Only the Newton-Cotes scheme needs a1_ and scratch_.
  std::vector<Vec3> x_start_, v_start_, f_start_, a1_, scratch_;
  std::vector<ObstacleContact> contacts_;  // nodes touching an obstacle now; sized once
  std::vector<Vec3> contact_impulse_;      // per obstacle, N s, this step
  std::vector<Vec3> pair_impulse_;         // per contact pair, N s, this step
  std::shared_ptr<DeformableContactWorkspace> deformable_;  // null without contact pairs
  double size_scale_ = 1.0;                                 // m, diagonal of the rest bounding box
  std::vector<double> shortest_edge_;   // m per node, for the runaway guard (runaway_guard.hpp)
  double shortest_edge_overall_ = 0.0;  // m, their smallest
  // Inertia of each node in the pseudo-dynamics: its mass, or in static mode a fictitious
  // mass that gives every node the same Gershgorin frequency (inertia_ empty: the masses).
  std::vector<double> inertia_;
};

}  // namespace phymul
