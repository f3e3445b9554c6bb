#include "mesh/surface_check.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <deque>
#include <map>
#include <unordered_map>

#include "mesh/spatial_hash.hpp"

namespace phymul {
namespace {

using Edge = std::pair<int, int>;  // (smaller, larger) point index

Edge edge_of(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

Triangle triangle_of(const Cell& c) { return {c.nodes[0], c.nodes[1], c.nodes[2]}; }

// Each undirected edge with the triangles using it, in triangle order.
std::map<Edge, std::vector<int>> edge_triangles(const std::vector<Triangle>& t) {
  std::map<Edge, std::vector<int>> edges;
  for (int k = 0; k < int(t.size()); ++k)
    for (int e = 0; e < 3; ++e) edges[edge_of(t[k][e], t[k][(e + 1) % 3])].push_back(k);
  return edges;
}

// Whether triangle t runs along the edge a -> b (its orientation there).
bool runs(const Triangle& t, int a, int b) {
  for (int e = 0; e < 3; ++e)
    if (t[e] == a && t[(e + 1) % 3] == b) return true;
  return false;
}

void degenerate(const Mesh& mesh, const std::vector<Triangle>& t, SurfaceCheck& out,
                size_t max_problems) {
  double mean_edge = 0.0;
  for (const Triangle& k : t)
    for (int e = 0; e < 3; ++e)
      mean_edge += (mesh.points[k[e]] - mesh.points[k[(e + 1) % 3]]).norm();
  mean_edge /= double(3 * std::max<size_t>(t.size(), 1));
  for (size_t k = 0; k < t.size() && out.problems.size() < max_problems; ++k) {
    const Triangle& c = t[k];
    const double twice_area =
        (mesh.points[c[1]] - mesh.points[c[0]]).cross(mesh.points[c[2]] - mesh.points[c[0]]).norm();
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2] ||
        !(twice_area > 1e-12 * mean_edge * mean_edge))
      out.problems.push_back(
          fmt::format("triangle {} ({}, {}, {}) is degenerate (zero area)", k, c[0], c[1], c[2]));
  }
}

void manifold(const std::map<Edge, std::vector<int>>& edges, SurfaceCheck& out,
              size_t max_problems) {
  for (const auto& [edge, users] : edges) {
    if (out.problems.size() >= max_problems) return;
    if (users.size() == 1)
      out.problems.push_back(
          fmt::format("edge ({}, {}) belongs to triangle {} only: the surface "
                      "is not closed",
                      edge.first, edge.second, users[0]));
    else if (users.size() > 2)
      out.problems.push_back(
          fmt::format("edge ({}, {}) is shared by {} triangles ({}): the "
                      "surface is not manifold",
                      edge.first, edge.second, users.size(), fmt::join(users, ", ")));
  }
}

// Flips triangles so that each edge is run once each way (breadth first from triangle 0 of
// each connected piece). Returns the flipped count, or -1 when no orientation fits (a
// one-sided surface).
long orient(std::vector<Triangle>& t, const std::map<Edge, std::vector<int>>& edges) {
  std::vector<int> state(t.size(), 0);  // 0 unseen, 1 kept, 2 flipped
  long flipped = 0;
  for (size_t start = 0; start < t.size(); ++start) {
    if (state[start]) continue;
    state[start] = 1;
    std::deque<int> queue{int(start)};
    while (!queue.empty()) {
      const int k = queue.front();
      queue.pop_front();
      for (int e = 0; e < 3; ++e) {
        const int a = t[k][e], b = t[k][(e + 1) % 3];
        for (int other : edges.at(edge_of(a, b))) {
          if (other == k) continue;
          const bool consistent = runs(t[other], b, a);
          if (state[other]) {
            if (!consistent) return -1;
            continue;
          }
          if (!consistent) {
            std::swap(t[other][1], t[other][2]);
            ++flipped;
          }
          state[other] = consistent ? 1 : 2;
          queue.push_back(other);
        }
      }
    }
  }
  return flipped;
}

double enclosed_volume(const Mesh& mesh, const std::vector<Triangle>& t) {
  double six = 0.0;
  for (const Triangle& k : t)
    six += mesh.points[k[0]].dot(mesh.points[k[1]].cross(mesh.points[k[2]]));
  return six / 6.0;
}

// Whether segment p q crosses triangle (a, b, c) at a point inside both (not at an end).
bool segment_crosses(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const double dp = n.dot(p - a), dq = n.dot(q - a);
  if (!(dp * dq < 0.0)) return false;  // both on one side, or touching the plane
  const Vec3 x = p + (dp / (dp - dq)) * (q - p);
  const double u = n.dot((b - a).cross(x - a)), v = n.dot((c - b).cross(x - b)),
               w = n.dot((a - c).cross(x - c));
  return (u > 0.0 && v > 0.0 && w > 0.0) || (u < 0.0 && v < 0.0 && w < 0.0);
}

bool share_point(const Triangle& s, const Triangle& t) {
  for (int i : s)
    for (int j : t)
      if (i == j) return true;
  return false;
}

bool triangles_cross(const Mesh& mesh, const Triangle& s, const Triangle& t) {
  const auto& x = mesh.points;
  for (int e = 0; e < 3; ++e) {
    if (segment_crosses(x[s[e]], x[s[(e + 1) % 3]], x[t[0]], x[t[1]], x[t[2]])) return true;
    if (segment_crosses(x[t[e]], x[t[(e + 1) % 3]], x[s[0]], x[s[1]], x[s[2]])) return true;
  }
  return false;
}

// Triangles sharing no point whose edges cross the other (a spatial hash finds the pairs
// near enough to meet).
void self_intersections(const Mesh& mesh, const std::vector<Triangle>& t, SurfaceCheck& out,
                        size_t max_problems) {
  double reach = 0.0;  // largest centroid-to-corner distance
  std::vector<Vec3> centroid(t.size());
  for (size_t k = 0; k < t.size(); ++k) {
    centroid[k] = (mesh.points[t[k][0]] + mesh.points[t[k][1]] + mesh.points[t[k][2]]) / 3.0;
    for (int i : t[k]) reach = std::max(reach, (mesh.points[i] - centroid[k]).norm());
  }
  TriangleHash hash;
  hash.reserve(t.size());
  hash.build(t, mesh.points, reach);  // cells of 2 reach: meeting triangles are neighbours
  for (size_t k = 0; k < t.size() && out.problems.size() < max_problems; ++k)
    hash.around(centroid[k], [&](int other) {
      if (size_t(other) <= k || out.problems.size() >= max_problems) return;
      if (share_point(t[k], t[size_t(other)])) return;
      if (triangles_cross(mesh, t[k], t[size_t(other)]))
        out.problems.push_back(fmt::format("triangles {} and {} intersect", k, other));
    });
}

}  // namespace

SurfaceCheck check_closed_surface(Mesh& mesh, size_t max_problems) {
  SurfaceCheck out;
  std::vector<Triangle> t;
  for (const Cell& c : mesh.cells) {
    if (c.type != CellType::triangle) {
      out.problems.push_back(fmt::format("cell {} is a {}: a surface holds triangles only",
                                         t.size(), cell_type_name(c.type)));
      return out;
    }
    t.push_back(triangle_of(c));
  }
  if (t.size() < 4) {
    out.problems.push_back(
        fmt::format("{} triangles cannot close a surface (at least 4)", t.size()));
    return out;
  }
  degenerate(mesh, t, out, max_problems);
  const auto edges = edge_triangles(t);
  manifold(edges, out, max_problems);
  if (!out.problems.empty()) return out;
  const std::vector<Triangle> given = t;
  const long flipped = orient(t, edges);
  if (flipped < 0) {
    out.problems.push_back("no orientation fits every triangle: the surface is one-sided");
    return out;
  }
  self_intersections(mesh, t, out, max_problems);
  if (!out.problems.empty()) return out;
  if (enclosed_volume(mesh, t) < 0.0)
    for (Triangle& k : t) std::swap(k[1], k[2]);
  // Reported against the file: which triangles end up turned from how it gave them.
  size_t turned = 0;
  for (size_t k = 0; k < t.size(); ++k) turned += t[k] != given[k];
  if (turned == t.size())
    out.repairs.push_back("every triangle flipped: the surface was inside out (normals inward)");
  else if (turned > 0)
    out.repairs.push_back(
        fmt::format("{} triangles flipped to agree with their neighbours and "
                    "face outward",
                    turned));
  for (size_t k = 0; k < t.size(); ++k)
    for (int e = 0; e < 3; ++e) mesh.cells[k].nodes[size_t(e)] = t[k][size_t(e)];
  return out;
}

size_t merge_duplicate_points(Mesh& mesh) {
  struct Key {
    std::array<std::uint64_t, 3> bits;
    bool operator==(const Key&) const = default;
  };
  struct Hash {
    size_t operator()(const Key& k) const {
      return size_t(k.bits[0] * 0x9E3779B97F4A7C15ull ^ k.bits[1] * 0xC2B2AE3D27D4EB4Full ^
                    k.bits[2] * 0x165667B19E3779F9ull);
    }
  };
  std::unordered_map<Key, int, Hash> first;
  first.reserve(mesh.points.size());
  std::vector<int> to(mesh.points.size());
  std::vector<Vec3> kept;
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    Key key{};
    for (int a = 0; a < 3; ++a) {
      const double c = mesh.points[i][a] == 0.0 ? 0.0 : mesh.points[i][a];  // -0 is 0
      std::memcpy(&key.bits[size_t(a)], &c, sizeof c);
    }
    const auto [at, inserted] = first.emplace(key, int(kept.size()));
    if (inserted) kept.push_back(mesh.points[i]);
    to[i] = at->second;
  }
  const size_t merged = mesh.points.size() - kept.size();
  for (Cell& c : mesh.cells)
    for (int k = 0; k < node_count(c.type); ++k)
      c.nodes[size_t(k)] = to[size_t(c.nodes[size_t(k)])];
  mesh.points = std::move(kept);
  return merged;
}

}  // namespace phymul
