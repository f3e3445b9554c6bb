// Nested dissection by coordinate bisection: split the nodes at the median coordinate along
// their longest extent; the nodes of the upper half that touch the lower half form the
// separator, numbered after both halves, which are dissected recursively. On a structured
// grid the separator is exactly one plane of nodes.
#include "fem/ordering.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <span>

namespace phymul::fem {

namespace {

constexpr std::size_t kLeafNodes = 16;  // below this the order hardly matters

struct Graph {
  std::vector<int> offsets;
  std::vector<int> neighbours;
  std::span<const int> of(int node) const {
    return {neighbours.data() + offsets[node], std::size_t(offsets[node + 1] - offsets[node])};
  }
};

Graph node_graph(const SparseMatrix& lower, const std::vector<int>& group, int nodes) {
  std::vector<std::vector<int>> adjacent(nodes);
  for (int j = 0; j < lower.outerSize(); ++j) {
    for (int v = lower.outerIndexPtr()[j]; v < lower.outerIndexPtr()[j + 1]; ++v) {
      const int a = group[lower.innerIndexPtr()[v]], b = group[j];
      if (a == b) continue;
      adjacent[a].push_back(b);
      adjacent[b].push_back(a);
    }
  }
  Graph g{{0}, {}};
  for (auto& list : adjacent) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    g.neighbours.insert(g.neighbours.end(), list.begin(), list.end());
    g.offsets.push_back(int(g.neighbours.size()));
  }
  return g;
}

class Dissection {
 public:
  Dissection(const Graph& graph, const std::vector<Vec3>& position)
      : graph_(graph), position_(position), stamp_(position.size(), -1) {}

  // Appends the nodes of `part` (reordered in place) to `order`, separators last.
  void run(std::span<int> part, std::vector<int>& order) {
    if (part.size() <= kLeafNodes) {
      order.insert(order.end(), part.begin(), part.end());
      return;
    }
    const std::size_t lower = split(part);
    if (lower == 0 || lower == part.size()) {  // all on one coordinate: cannot split
      order.insert(order.end(), part.begin(), part.end());
      return;
    }
    const int id = next_id_++;
    for (std::size_t i = 0; i < lower; ++i) stamp_[part[i]] = id;
    // Upper nodes touching the lower half go to the end of the part: the separator.
    const auto upper = part.subspan(lower);
    const auto separator = std::stable_partition(upper.begin(), upper.end(), [&](int n) {
      const auto adjacent = graph_.of(n);
      return std::none_of(adjacent.begin(), adjacent.end(), [&](int m) { return stamp_[m] == id; });
    });
    const std::size_t interior = std::size_t(separator - upper.begin());
    run(part.first(lower), order);
    run(upper.first(interior), order);
    order.insert(order.end(), separator, upper.end());
  }

 private:
  // Puts the nodes below the median coordinate (longest axis) first; returns their count.
  std::size_t split(std::span<int> part) const {
    Eigen::AlignedBox3d box;
    for (int n : part) box.extend(position_[n]);
    int axis = 0;
    box.sizes().maxCoeff(&axis);
    const auto coordinate = [&](int n) { return position_[n][axis]; };
    const auto middle = part.begin() + part.size() / 2;
    std::nth_element(part.begin(), middle, part.end(),
                     [&](int a, int b) { return coordinate(a) < coordinate(b); });
    const double median = coordinate(*middle);
    const auto cut =
        std::partition(part.begin(), part.end(), [&](int n) { return coordinate(n) < median; });
    return std::size_t(cut - part.begin());
  }

  const Graph& graph_;
  const std::vector<Vec3>& position_;
  std::vector<int> stamp_;
  int next_id_ = 0;
};

}  // namespace

std::vector<int> nested_dissection(const SparseMatrix& lower, const NodeGeometry& geometry) {
  const int nodes = int(geometry.position.size());
  const Graph graph = node_graph(lower, geometry.group, nodes);
  std::vector<char> used(nodes, 0);
  for (int g : geometry.group) used[g] = 1;
  std::vector<int> part;
  for (int n = 0; n < nodes; ++n) {
    if (used[n]) part.push_back(n);
  }
  std::vector<int> node_order;
  Dissection(graph, geometry.position).run(part, node_order);

  // Unknowns follow their nodes; within a node, in increasing index.
  std::vector<std::vector<int>> unknowns(nodes);
  for (std::size_t u = 0; u < geometry.group.size(); ++u)
    unknowns[geometry.group[u]].push_back(int(u));
  std::vector<int> order;
  order.reserve(geometry.group.size());
  for (int n : node_order) order.insert(order.end(), unknowns[n].begin(), unknowns[n].end());
  return order;
}

}  // namespace phymul::fem
