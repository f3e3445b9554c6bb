#include "solver/runaway_guard.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/thread_team.hpp"

namespace phymul {

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

// The parallel look's test without the square root and the division of runaway_ratio: a
// node whose squared step is below (1 - 1e-9) of its squared bound is within the bound by
// runaway_ratio's rounding too; the others (near it, beyond it, not finite) take the exact
// test, so that the look decides exactly as runaway_ratio would.
bool surely_within(const ShapeMemory& m, int k, std::span<const double> edges,
                   std::span<const Vec3> before, std::span<const Vec3> after) {
  const int i = m.nodes[k];
  if (!std::isfinite(edges[i])) return true;
  const auto nb = m.neighbours.row(k);
  Vec3 mean = Vec3::Zero();
  for (int j : nb) mean += after[j] - before[j];
  mean /= double(nb.size());
  const double bound = kRunawayFraction * edges[i];
  return (after[i] - before[i] - mean).squaredNorm() < (1.0 - 1e-9) * bound * bound;
}

// A node moves against its neighbours' mean step by at most twice the largest step of any
// node: while that stays below every node's bound (by 1e-6, far more than the per-node
// look's rounding), that look cannot find a runaway and is skipped. One sequential pass
// instead of a gather over every neighbour: the step's usual case.
bool surely_no_runaway(std::span<const double> edges, std::span<const Vec3> before,
                       std::span<const Vec3> after) {
  const int n = int(after.size());
  double largest = 0.0, shortest = std::numeric_limits<double>::infinity();
  bool finite = true;
  auto look = [&](int i, double& most, double& least, bool& all_finite) {
    const double step2 = (after[i] - before[i]).squaredNorm();
    all_finite = all_finite && std::isfinite(step2);
    most = std::max(most, step2);
    least = std::min(least, edges[i]);
  };
  if (team_pays(n, 4096)) {
#pragma omp parallel for schedule(static) reduction(max : largest) reduction(min : shortest) \
    reduction(&& : finite)
    for (int i = 0; i < n; ++i) look(i, largest, shortest, finite);
  } else {
    for (int i = 0; i < n; ++i) look(i, largest, shortest, finite);
  }
  return finite && steps_surely_within_bound(largest, shortest);
}

}  // namespace

std::optional<Runaway> find_runaway(const Model& model, std::span<const double> edges,
                                    std::span<const Vec3> before, std::span<const Vec3> after) {
  // Relative to the mean step of its own neighbours: rigid motion, a uniform inflation (a
  // filling bladder) or a prescribed push move a node with its neighbourhood, the unstable
  // mode against it. A parallel look first (read only); the first runaway is then found in
  // order, so the node named does not depend on the thread count.
  if (surely_no_runaway(edges, before, after)) return std::nullopt;
  for (const ShapeMemory& m : model.shape_memory) {
    const int count = int(m.nodes.size());
    bool all_well = true;
    auto well = [&](int k) {
      double moved = 0.0;
      return surely_within(m, k, edges, before, after) ||
             runaway_ratio(m, k, edges, before, after, moved) <= 1.0;
    };
    if (team_pays(count, 4096)) {
#pragma omp parallel for schedule(static) reduction(&& : all_well)
      for (int k = 0; k < count; ++k) all_well = all_well && well(k);
    } else {
      for (int k = 0; k < count && all_well; ++k) all_well = well(k);
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
