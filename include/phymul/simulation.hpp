// Running a model: explicit dynamics (DESIGN 2.3) and static relaxation to equilibrium, as
// free functions of a const Model and the Data they advance, and Simulator, a convenience
// that owns one of each.
#pragma once

#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "phymul/data.hpp"
#include "phymul/forces.hpp"
#include "phymul/model.hpp"

namespace phymul {

// A run that became unstable: names the node, component and time, and what to change.
class InstabilityError : public std::runtime_error {
 public:
  InstabilityError(const std::string& message, int node, double time)
      : std::runtime_error(message), node(node), time(time) {}
  int node;
  double time;
};

// A Data ready to step: at rest with the driven bodies at their t = 0 pose, the position
// constraints applied, the forces evaluated at t = 0, dt from the settings (`dt: auto`: a
// share of the stability estimate, Data::stable_dt). The model must be finalized for its
// settings (std::invalid_argument otherwise). Allocates: for set-up, not inside a step.
Data make_data(const Model& model);

// One explicit step of data.dt with the model's integrator; loads at the new time. An
// unstable step throws InstabilityError and leaves data as it was before it. Allocates
// nothing.
void step(const Model& model, Data& data);

struct StaticResult {
  bool converged = false;
  long iterations = 0;    // steps of pseudo-dynamics, all load steps together
  double residual = 0.0;  // N, largest free residual force at the end
};

// Called every 256 relaxation iterations and at the end of each load step with the load
// step's iterations and the residual (N); it may throw to stop the solve there.
using RelaxProgress = std::function<void(long, double)>;

// Relaxes to equilibrium with the loads of load_time (s); stops when the largest free residual
// force is below tolerance (N) or after max_iterations.
StaticResult relax(const Model& model, Data& data, double load_time, long max_iterations,
                   const RelaxProgress& progress, double tolerance);
// The settings' static mode: load steps up to their duration (data.static_progress from the
// start).
StaticResult solve_static(const Model& model, Data& data, const RelaxProgress& progress = {});
// Continues a static solve from data.static_progress (a restored checkpoint), as if never
// stopped.
StaticResult resume_static(const Model& model, Data& data, const RelaxProgress& progress = {});

double kinetic_energy(const Model& model, const Data& data);  // J, with the model's inertias
// Largest nodal force (N) on the free axes, less the part a volume constraint or a contact
// balances. Uses data's workspace.
double max_residual_force(const Model& model, Data& data);
// Force (N) each position constraint exerts on its node, on the held axes (zero on free
// ones): minus the forces there, the pressure of the volume constraints included. At
// equilibrium they balance every load. Allocates.
std::vector<Vec3> support_reactions(const Model& model, const Data& data);
// Enclosed volume (m^3) of every component with a closed boundary, in component order (NaN
// for the others).
std::vector<double> component_volumes(const Model& model, const Data& data);
// Force (N) the obstacle exerts on the body: minus Data::f on the free axes, less the volume
// constraints' pressures, summed over the nodes it acts on that touch its surface (within
// 1e-12 m, or put on it by the last step's contact stage: Data::obstacle_touching) at
// Data::time. Valid at equilibrium only (after relax), where the contact is what balances
// what is left on them.
Vec3 obstacle_force(const Model& model, const Data& data, int obstacle);

// Largest stable time step (s) of the explicit schemes for this model, from a Gershgorin
// bound on the elastic stiffness over the node masses, or over these inertias (kg per node).
double stable_time_step(const Model& model);
double stable_time_step(const Model& model, const std::vector<double>& inertia);
// Largest stable step (s) of central differences for the highest angular frequency omega
// (rad/s) under mass-proportional damping (1/s); infinity when omega is zero.
double verlet_stable_step(double omega, double damping);
// kg: what the settings' mass scaling adds to the true masses, summed over the nodes.
double added_inertia(const Model& model);

// The highest angular frequency of the forces linearised at `data`, over these inertias (kg
// per node), on the free axes (simulation.dt_estimate: power). omega^2 lies between
// `rayleigh` and `rayleigh + residual` once the iteration has found the top eigenvector (the
// residual bounds the distance to an eigenvalue); omega() takes the top, the safe side.
struct FrequencyEstimate {
  double rayleigh = 0.0;  // (rad/s)^2, Rayleigh quotient of the last iterate
  double residual = 0.0;  // (rad/s)^2, |A y - rayleigh y| for the unit iterate y
  int iterations = 0;
  double omega() const { return std::sqrt(std::max(rayleigh + residual, 0.0)); }
};
// Power iteration, the force Jacobian by central differences of the force pass; stops when
// the residual is below 1e-4 of the quotient or after max_iterations (two force passes each).
// Allocates: for set-up, not inside a step.
FrequencyEstimate highest_frequency(const Model& model, const Data& data,
                                    const std::vector<double>& inertia, double load_time = 0.0,
                                    int max_iterations = 400);

// The compiled model as one reference-FEM problem at its settings' end time: its fem cells
// (hexahedra, tetrahedra; wedges already cut) with each object's law, E and nu; the fixed and
// prescribed components at duration (scaled by fem's load steps); dead nodal loads: the
// applied forces at duration plus gravity on the lumped node masses (what the relaxation
// applies). Stitched objects share their merged nodes.
fem::Problem newton_problem(const Model& model);

// A Model and a Data together, for programs that run one simulation: the functions above as
// methods. Finalizes the model first where its settings changed since.
class Simulator {
 public:
  explicit Simulator(Model model);

  const Model& model() const { return model_; }
  Data& data() { return data_; }
  const Data& data() const { return data_; }
  double dt() const { return data_.dt; }
  double stable_dt() const { return data_.stable_dt; }
  void set_dt(double dt) { data_.dt = dt; }  // s

  void step() { phymul::step(model_, data_); }
  StaticResult relax(double load_time, long max_iterations, const RelaxProgress& progress,
                     double tolerance) {
    return phymul::relax(model_, data_, load_time, max_iterations, progress, tolerance);
  }
  StaticResult relax(double load_time, long max_iterations, const RelaxProgress& progress = {}) {
    return relax(load_time, max_iterations, progress, model_.settings.tolerance);
  }
  StaticResult solve_static(const RelaxProgress& progress = {}) {
    return phymul::solve_static(model_, data_, progress);
  }
  StaticResult resume_static(const RelaxProgress& progress = {}) {
    return phymul::resume_static(model_, data_, progress);
  }
  // Puts back a saved Data (a checkpoint's): it must fit the model (every array at
  // allocate_data's size), else std::invalid_argument naming the member.
  void restore(const Data& saved);

  double kinetic_energy() const { return phymul::kinetic_energy(model_, data_); }
  double added_inertia() const { return phymul::added_inertia(model_); }
  const std::vector<double>& inertia() const { return model_.inertia; }  // kg per node
  double max_residual_force() { return phymul::max_residual_force(model_, data_); }
  std::vector<Vec3> support_reactions() const { return phymul::support_reactions(model_, data_); }
  std::vector<double> component_volumes() const { return phymul::component_volumes(model_, data_); }

 private:
  Model model_;
  Data data_;
};

}  // namespace phymul
