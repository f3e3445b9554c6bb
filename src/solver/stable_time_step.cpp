#include <algorithm>
#include <cmath>
#include <limits>

#include "forces/explicit_fem.hpp"
#include "phymul/simulation.hpp"

namespace phymul {

double stable_time_step(const Model& model) { return stable_time_step(model, model.mass); }

double stable_time_step(const Model& model, const std::vector<double>& inertia) {
  const std::vector<double> row = stiffness_row_sums(model);
  double omega2 = 0.0;
  for (int i = 0; i < model.node_count(); ++i) omega2 = std::max(omega2, row[i] / inertia[i]);
  return verlet_stable_step(std::sqrt(omega2), model.damping);
}

}  // namespace phymul
