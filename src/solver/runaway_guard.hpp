// Catches an explicit integration running away before its numbers overflow.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "phymul/model.hpp"

namespace phymul {

// An unstable explicit scheme amplifies its highest-frequency mode, in which neighbouring
// nodes move against each other, by a growing factor per step (about 34 at three times the
// stable step). The guard flags the step in which a free node moves, relative to the mean
// motion of its neighbours, more than kRunawayFraction of its shortest rest edge: its cells
// are then inside out, and the growth makes the next step overflow. Legitimate violent runs
// (a floppy membrane filled fast, a chamber squeezed) reach 1.3 edges; rigid motion and
// uniform inflation move a node with its neighbours and count for nothing.
constexpr double kRunawayFraction = 2.0;

// (Each node's shortest rest edge, which the guard measures by, is Model::runaway_edge.)

struct Runaway {
  int node;
  double moved;  // m in one step, relative to its neighbours' mean step
  double edge;   // m, the node's shortest rest edge
};

// No node can have run away when the largest squared step of any node in it (finite) is
// below a quarter of the squared bound of the shortest edge: a node and its neighbours' mean
// then moved less than the bound apart.
inline bool steps_surely_within_bound(double largest_step2, double shortest_edge) {
  const double bound = kRunawayFraction * shortest_edge;
  return 4.0 * largest_step2 < (1.0 - 1e-6) * bound * bound;
}

// Compares the positions before and after one step; allocation-free.
std::optional<Runaway> find_runaway(const Model& model, std::span<const double> edges,
                                    std::span<const Vec3> before, std::span<const Vec3> after);

}  // namespace phymul
