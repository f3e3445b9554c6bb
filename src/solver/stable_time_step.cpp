#include <algorithm>
#include <cmath>
#include <limits>

#include "forces/explicit_fem.hpp"
#include "phymul/simulator.hpp"

namespace phymul {

std::vector<double> stiffness_row_sums(const Model& model) {
  // Row sums of |df/dx| per node (rotation terms neglected): a node's own pull K(a - x)
  // gives K on itself and K/n on each of its n neighbours; with the reaction option each
  // node it neighbours adds its own row share 2K/n.
  std::vector<double> row(size_t(model.node_count()), 0.0);
  for (const ShapeMemory& m : model.shape_memory) {
    for (int k = 0; k < int(m.nodes.size()); ++k) {
      row[m.nodes[k]] += 2.0 * m.stiffness;
      if (!m.reaction) continue;
      const auto nb = m.neighbours.row(k);
      for (int j : nb) row[j] += 2.0 * m.stiffness / double(nb.size());
    }
  }
  // A fibre segment is a spring between two nodes: K on each and K across.
  for (const FibreBundle& fibres : model.fibres)
    for (int p = 0; p < fibres.polylines.rows(); ++p) {
      const auto line = fibres.polylines.row(p);
      for (size_t k = 0; k + 1 < line.size(); ++k) {
        row[line[k]] += 2.0 * fibres.stiffness;
        row[line[k + 1]] += 2.0 * fibres.stiffness;
      }
    }
  for (const ExplicitFem& e : model.explicit_fem) add_explicit_fem_rows(e, row);
  return row;
}

double stable_time_step(const Model& model) { return stable_time_step(model, model.mass); }

double stable_time_step(const Model& model, const std::vector<double>& inertia) {
  const std::vector<double> row = stiffness_row_sums(model);
  double omega2 = 0.0;
  for (int i = 0; i < model.node_count(); ++i) omega2 = std::max(omega2, row[i] / inertia[i]);
  return verlet_stable_step(std::sqrt(omega2), model.damping);
}

}  // namespace phymul
