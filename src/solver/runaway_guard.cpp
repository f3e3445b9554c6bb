#include "solver/runaway_guard.hpp"

#include <cmath>
#include <limits>

namespace phymul {

std::vector<double> runaway_edges(const Model& model) {
  const std::vector<Vec3>& rest = model.rest_position;
  constexpr double kNone = std::numeric_limits<double>::infinity();
  std::vector<double> edge(rest.size(), kNone);
  for (const ShapeMemory& m : model.shape_memory)
    for (int k = 0; k < int(m.nodes.size()); ++k) {
      const int i = m.nodes[k];
      for (int j : m.neighbours.row(k)) edge[i] = std::min(edge[i], (rest[j] - rest[i]).norm());
    }
  for (size_t i = 0; i < rest.size(); ++i)
    if (!(edge[i] > 0.0) || !(model.inverse_mass[i].array() > 0.0).all()) edge[i] = kNone;
  return edge;
}

std::optional<Runaway> find_runaway(const Model& model, std::span<const double> edges,
                                    std::span<const Vec3> before, std::span<const Vec3> after) {
  // Relative to the mean step of its own neighbours: rigid motion, a uniform inflation (a
  // filling bladder) or a prescribed push move a node with its neighbourhood, the unstable
  // mode against it.
  for (const ShapeMemory& m : model.shape_memory)
    for (int k = 0; k < int(m.nodes.size()); ++k) {
      const int i = m.nodes[k];
      if (!std::isfinite(edges[i])) continue;
      const auto nb = m.neighbours.row(k);
      Vec3 mean = Vec3::Zero();
      for (int j : nb) mean += after[j] - before[j];
      mean /= double(nb.size());
      const double moved = (after[i] - before[i] - mean).norm();
      if (!(moved <= kRunawayFraction * edges[i])) return Runaway{i, moved, edges[i]};
    }
  return std::nullopt;
}

}  // namespace phymul
