#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "model/finalize.hpp"

namespace phymul {
namespace {

int root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

std::vector<std::vector<int>> doubled_groups(const Model& model) {
  const int n = model.node_count();
  std::vector<int> parent(static_cast<size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& [a, b] : model.doubled_pairs) {
    if (a < 0 || a >= n || b < 0 || b >= n)
      throw std::invalid_argument(fmt::format(
          "doubled nodes: pair ({}, {}) is out of range (the model has {} nodes)", a, b, n));
    if (a == b)
      throw std::invalid_argument(fmt::format("doubled nodes: node {} is paired with itself", a));
    parent[root(parent, std::max(a, b))] = root(parent, std::min(a, b));
  }
  std::vector<std::vector<int>> groups;
  std::vector<int> group_of(size_t(n), -1);
  for (const auto& pair : model.doubled_pairs)
    for (int i : pair) {
      const int r = root(parent, i);
      if (group_of[r] < 0) {
        group_of[r] = int(groups.size());
        groups.emplace_back();
      }
      groups[group_of[r]].push_back(i);
    }
  for (auto& g : groups) {
    std::sort(g.begin(), g.end());
    g.erase(std::unique(g.begin(), g.end()), g.end());
  }
  std::sort(groups.begin(), groups.end());
  return groups;
}

void finalize_doubled(Model& model) {
  model.doubled = Adjacency{};
  model.doubled_leader.clear();
  for (const auto& group : doubled_groups(model)) {
    if (!model.rigid_body_of.empty() && model.rigid_body_of[group.front()] >= 0)
      continue;  // moved with its rigid body
    std::array<int, 3> leader{-1, -1, -1};
    for (int a = 0; a < 3; ++a)
      for (int i : group)
        if (leader[a] < 0 && model.inverse_mass[i][a] == 0.0) leader[a] = i;
    for (int a = 0; a < 3; ++a)
      if (leader[a] >= 0)
        for (int i : group) model.inverse_mass[i][a] = 0.0;
    model.doubled.indices.insert(model.doubled.indices.end(), group.begin(), group.end());
    model.doubled.offsets.push_back(int(model.doubled.indices.size()));
    model.doubled_leader.push_back(leader);
  }
}

void add_doubled_nodes(Model& model, const std::vector<std::array<int, 2>>& pairs) {
  for (const auto& [a, b] : pairs)
    if (a < 0 || a >= model.node_count() || b < 0 || b >= model.node_count() || a == b)
      throw std::invalid_argument(
          fmt::format("doubled nodes: pair ({}, {}) is invalid (the model has {} nodes)", a, b,
                      model.node_count()));
  model.doubled_pairs.insert(model.doubled_pairs.end(), pairs.begin(), pairs.end());
}

}  // namespace phymul
