// What finalize derives from the rest besides the bodies and doubled groups: the volume
// constraints' indexes, the stiffness bounds, the runaway guard's edges.
#include <algorithm>
#include <cmath>
#include <limits>

#include "model/explicit_fem_cells.hpp"
#include "model/finalize.hpp"

namespace phymul {

void index_volume_faces(VolumeConstraint& c) {
  c.incident_start.clear();
  c.incident.clear();
  const size_t n = c.nodes.size();
  std::vector<int> start(n + 1, 0);
  auto local = [&](int node) {
    const auto at = std::lower_bound(c.nodes.begin(), c.nodes.end(), node);
    return at != c.nodes.end() && *at == node ? size_t(at - c.nodes.begin()) : n;
  };
  for (const Triangle& t : c.triangles)
    for (int node : t) {
      const size_t k = local(node);
      if (k == n) return;  // a corner outside `nodes`: keep the scatter
      ++start[k + 1];
    }
  for (size_t k = 0; k < n; ++k) start[k + 1] += start[k];
  std::vector<std::array<int, 2>> incident(size_t(start.back()));
  std::vector<int> next(start.begin(), start.end() - 1);
  for (const Triangle& t : c.triangles)  // in triangle order: the scatter's order of sums
    for (int p = 0; p < 3; ++p)
      incident[size_t(next[local(t[size_t(p)])]++)] = {t[size_t(p + 1) % 3], t[size_t(p + 2) % 3]};
  c.incident_start = std::move(start);
  c.incident = std::move(incident);
}

void index_shared_volume_nodes(Model& model) {
  for (size_t k = 0; k < model.volumes.size(); ++k) {
    VolumeConstraint& c = model.volumes[k];
    c.shared.clear();
    for (size_t l = 0; l < k; ++l) {  // both sorted: a merge
      const std::vector<int>& o = model.volumes[l].nodes;
      for (size_t p = 0, q = 0; p < c.nodes.size() && q < o.size();) {
        if (c.nodes[p] < o[q]) {
          ++p;
        } else if (o[q] < c.nodes[p]) {
          ++q;
        } else {
          c.shared.push_back({int(l), int(p), int(q)});
          ++p, ++q;
        }
      }
    }
  }
}

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
  for (const SpringSupport& springs : model.springs)
    for (int i : springs.nodes) row[size_t(i)] += springs.stiffness;
  return row;
}

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

}  // namespace phymul
