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

namespace {

// How far memory node k moved against the mean step of its neighbours, over its edge bound.
double runaway_ratio(const ShapeMemory& m, int k, std::span<const double> edges,
                     std::span<const Vec3> before, std::span<const Vec3> after, double& moved) {
  const int i = m.nodes[k];
  if (!std::isfinite(edges[i])) return 0.0;
  const auto nb = m.neighbours.row(k);
  Vec3 mean = Vec3::Zero();
  for (int j : nb) mean += after[j] - before[j];
  mean /= double(nb.size());
  moved = (after[i] - before[i] - mean).norm();
  return moved / (kRunawayFraction * edges[i]);
}

}  // namespace

std::optional<Runaway> find_runaway(const Model& model, std::span<const double> edges,
                                    std::span<const Vec3> before, std::span<const Vec3> after) {
  // Relative to the mean step of its own neighbours: rigid motion, a uniform inflation (a
  // filling bladder) or a prescribed push move a node with its neighbourhood, the unstable
  // mode against it. A parallel look first (read only); the first runaway is then found in
  // order, so the node named does not depend on the thread count.
  for (const ShapeMemory& m : model.shape_memory) {
    const int count = int(m.nodes.size());
    bool all_well = true;
#pragma omp parallel for schedule(static) if (count >= 4096) reduction(&& : all_well)
    for (int k = 0; k < count; ++k) {
      double moved = 0.0;
      all_well = all_well && runaway_ratio(m, k, edges, before, after, moved) <= 1.0;
    }
    if (all_well) continue;
    for (int k = 0; k < count; ++k) {
      double moved = 0.0;
      if (!(runaway_ratio(m, k, edges, before, after, moved) <= 1.0))
        return Runaway{m.nodes[k], moved, edges[m.nodes[k]]};
    }
  }
  return std::nullopt;
}

}  // namespace phymul
