// Catches an explicit integration running away before its numbers overflow.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "phymul/model.hpp"

namespace phymul {

// An unstable explicit scheme amplifies its highest-frequency mode, in which neighbouring
// nodes move against each other, by a growing factor per step (about 34 at three times the
// stable step). The guard flags the step in which a free node moves, relative to its
// component's mean motion, more than kRunawayFraction of its shortest rest edge: a stable
// run moves nodes a small fraction of an element per step, while past that fraction the
// next step can already turn cells inside out.
constexpr double kRunawayFraction = 0.5;

// Per node: its shortest rest edge (m) where the guard watches it (a node with a shape
// memory, free on every axis), infinity elsewhere.
std::vector<double> runaway_edges(const Model& model);

struct Runaway {
  int node;
  double moved;  // m in one step, relative to the component's mean step
  double edge;   // m, the node's shortest rest edge
};

// Compares the positions before and after one step; allocation-free.
std::optional<Runaway> find_runaway(const Model& model, std::span<const double> edges,
                                    std::span<const Vec3> before, std::span<const Vec3> after);

}  // namespace phymul
