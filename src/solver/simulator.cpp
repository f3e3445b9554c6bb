// Data made ready to step, and Simulator, the convenience that owns a Model and its Data.
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "constraints/constraints.hpp"
#include "model/data_fields.hpp"
#include "model/workspace.hpp"
#include "phymul/simulation.hpp"
#include "solver/rigid.hpp"
#include "solver/step.hpp"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace phymul {
namespace {

// Building a model (meshes, adjacency, sorting) frees about half as much as the model and
// its data keep, and the allocator keeps those holes resident for the whole run: a fifth of
// the memory of a large model. Giving their pages back costs a few microseconds.
void release_free_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

}  // namespace

Data make_data(const Model& model) {
  if (!finalized(model)) throw_not_finalized();
  Data d = allocate_data(model);
  drift_rigid_bodies(model, d, 0.0, 0.0);  // driven bodies at their t = 0 pose
  const SimulationSpec& s = model.settings;
  // The power estimate takes the inertias the steps use; the Gershgorin bound takes them in
  // dynamics only (static relaxation's fictitious masses are not the run's).
  const bool scaled = s.mode == SolveMode::dynamic && s.mass_scaling_dt;
  d.stable_dt =
      s.dt_estimate == DtEstimate::power
          ? verlet_stable_step(highest_frequency(model, d, model.inertia).omega(), model.damping)
          : stable_time_step(model, scaled ? model.inertia : model.mass);
  d.dt = s.dt ? *s.dt : s.dt_safety * d.stable_dt;
  if (!std::isfinite(d.dt)) d.dt = 1e-3;  // no stiffness at all: any step is stable
  apply_position_constraints(model, d.controls, *d.work, d.x, 0.0,
                             d.work->f_start);  // free between steps
  compute_forces(model, d, 0.0);
  release_free_memory();
  return d;
}

double added_inertia(const Model& model) {
  double added = 0.0;
  for (size_t i = 0; i < model.inertia.size(); ++i) added += model.inertia[i] - model.mass[i];
  return added;
}

Simulator::Simulator(Model model) : model_(std::move(model)) {
  if (!finalized(model_)) finalize(model_);
  data_ = make_data(model_);
}

void Simulator::restore(const Data& saved) {
  const std::string mismatch = data_shape_mismatch(model_, saved);
  if (!mismatch.empty())
    throw std::invalid_argument("restore: the data does not fit the model: " + mismatch);
  assign_data(data_, saved);
}

}  // namespace phymul
