// Shared border nodes (paper, Fig. 1a): two components stitched by merging nodes. The
// merged node is listed by both components, so it feels the shape memory of each, each
// computed with that component's own neighbourhood.
#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "model/explicit_fem_cells.hpp"
#include "model/shape_memory_rest.hpp"
#include "phymul/model.hpp"

namespace phymul {
namespace {

int root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

void remap(std::vector<int>& ids, const std::vector<int>& to) {
  for (int& i : ids) i = to[i];
}

void remap(std::vector<Triangle>& triangles, const std::vector<int>& to) {
  for (Triangle& t : triangles)
    for (int& i : t) i = to[i];
}

void sort_unique(std::vector<int>& ids) {
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
}

// Refuses a merge inside one component: its cells would collapse.
void check_components(const Model& model, std::vector<int>& parent) {
  for (const Component& c : model.components) {
    std::vector<int> roots;
    for (int i : c.nodes) roots.push_back(root(parent, i));
    sort_unique(roots);
    if (roots.size() != c.nodes.size())
      throw std::invalid_argument(fmt::format(
          "stitch: two nodes of object '{}' would merge into one; lower the tolerance or "
          "select fewer nodes",
          c.name));
  }
}

}  // namespace

void stitch_nodes(Model& model, const std::vector<std::array<int, 2>>& pairs) {
  if (pairs.empty()) return;
  if (!model.prescribed.empty() || !model.forces.empty() || !model.pressures.empty() ||
      !model.obstacles.empty() || !model.doubled_pairs.empty() || !model.fibres.empty())
    throw std::invalid_argument(
        "stitch_nodes: stitch the components before adding loads, constraints and fibres");
  const int n = model.node_count();
  std::vector<int> parent(static_cast<size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& [a, b] : pairs) {
    if (a < 0 || a >= n || b < 0 || b >= n)
      throw std::invalid_argument(
          fmt::format("stitch: pair ({}, {}) is out of range (the model has {} nodes)", a, b, n));
    parent[root(parent, std::max(a, b))] = root(parent, std::min(a, b));
  }
  check_components(model, parent);

  // Survivors keep their order; each merged node takes the mass and the mass-weighted
  // rest position of its group.
  std::vector<int> to(size_t(n), -1);
  std::vector<Vec3> rest;
  std::vector<double> mass;
  for (int i = 0; i < n; ++i)
    if (root(parent, i) == i) {
      to[i] = int(rest.size());
      rest.push_back(Vec3::Zero());
      mass.push_back(0.0);
    }
  for (int i = 0; i < n; ++i) {
    const int k = to[root(parent, i)];
    to[i] = k;
    rest[k] += model.mass[i] * model.rest_position[i];
    mass[k] += model.mass[i];
  }
  for (size_t k = 0; k < rest.size(); ++k) rest[k] /= mass[k];
  model.rest_position = std::move(rest);
  model.mass = std::move(mass);

  for (Cell& cell : model.cells)
    for (int k = 0; k < node_count(cell.type); ++k) cell.nodes[k] = to[cell.nodes[k]];
  for (Component& c : model.components) {
    remap(c.nodes, to);
    remap(c.boundary, to);
    for (auto& [name, ids] : c.node_sets) remap(ids, to);
  }
  for (ShapeMemory& m : model.shape_memory) {
    remap(m.nodes, to);
    remap(m.neighbours.indices, to);
    memorise_rest_shape(m, model.rest_position);
  }
  // Finite elements keep their reference gradients: merged nodes lie within the stitch
  // tolerance of where they were computed.
  for (ExplicitFem& e : model.explicit_fem) {
    remap(e.cells, to);
    plan_explicit_fem(e);
  }
  for (VolumeConstraint& v : model.volumes) {
    remap(v.triangles, to);
    remap(v.nodes, to);
    sort_unique(v.nodes);
    v.target_volume = enclosed_volume(model.rest_position, v.triangles);
  }
}

std::vector<std::array<int, 2>> coincident_pairs(const Model& model, const std::vector<int>& from,
                                                 const std::vector<int>& to, double tolerance) {
  if (!(tolerance > 0.0))
    throw std::invalid_argument(
        fmt::format("stitch: the tolerance must be > 0 m (got {})", tolerance));
  // Sorted along x, each node scans the slab |dx| <= tolerance: fine for border sets.
  std::vector<std::pair<double, int>> sorted;
  for (int j : to) sorted.push_back({model.rest_position[j].x(), j});
  std::sort(sorted.begin(), sorted.end());
  std::vector<std::array<int, 2>> pairs;
  for (int i : from) {
    const Vec3& p = model.rest_position[i];
    auto it = std::lower_bound(sorted.begin(), sorted.end(), std::pair{p.x() - tolerance, -1});
    int best = -1;
    double best_distance = tolerance;
    for (; it != sorted.end() && it->first <= p.x() + tolerance; ++it) {
      const double d = (model.rest_position[it->second] - p).norm();
      if (it->second != i && d <= best_distance) best = it->second, best_distance = d;
    }
    if (best >= 0) pairs.push_back({i, best});
  }
  return pairs;
}

}  // namespace phymul
