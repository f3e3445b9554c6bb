#include "mesh/surface_check.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cstring>
#include <deque>
#include <span>
#include <unordered_map>

#include "mesh/spatial_hash.hpp"

namespace phymul {
namespace {

using Edge = std::pair<int, int>;  // (smaller, larger) point index

Edge edge_of(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

Triangle triangle_of(const Cell& c) { return {c.nodes[0], c.nodes[1], c.nodes[2]}; }

// Each undirected edge with the triangles using it, in triangle order; edges in (smaller,
// larger) order. Filed by smaller point (a counting sort: a map of 3 million edges took most
// of a million-triangle surface's reading time).
class EdgeTable {
 public:
  explicit EdgeTable(const std::vector<Triangle>& t) {
    int points = 0;
    for (const Triangle& k : t)
      for (int i : k) points = std::max(points, i + 1);
    start_.assign(size_t(points) + 1, 0);
    for (const Triangle& k : t)
      for (int e = 0; e < 3; ++e) ++start_[size_t(edge_of(k[e], k[(e + 1) % 3]).first) + 1];
    for (size_t i = 1; i < start_.size(); ++i) start_[i] += start_[i - 1];
    entries_.resize(3 * t.size());
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (int k = 0; k < int(t.size()); ++k)
      for (int e = 0; e < 3; ++e) {
        const Edge edge = edge_of(t[size_t(k)][e], t[size_t(k)][(e + 1) % 3]);
        entries_[size_t(fill[size_t(edge.first)]++)] = {edge.second, k};
      }
    for (size_t i = 0; i + 1 < start_.size(); ++i)
      std::sort(entries_.begin() + start_[i], entries_.begin() + start_[i + 1]);
    users_.resize(entries_.size());
    for (size_t j = 0; j < entries_.size(); ++j) users_[j] = entries_[j].second;
  }
  // The triangles using edge (a, b), in order.
  std::span<const int> users(Edge edge) const {
    const auto first = entries_.begin() + start_[size_t(edge.first)],
               last = entries_.begin() + start_[size_t(edge.first) + 1];
    const auto from = std::lower_bound(first, last, std::pair(edge.second, INT_MIN));
    const auto to = std::lower_bound(from, last, std::pair(edge.second + 1, INT_MIN));
    return {users_.data() + (from - entries_.begin()), size_t(to - from)};
  }
  // visit(edge, users) for every edge, in order.
  template <class Visit>
  void for_each(Visit visit) const {
    for (size_t a = 0; a + 1 < start_.size(); ++a)
      for (int j = start_[a]; j < start_[a + 1];) {
        int end = j;
        while (end < start_[a + 1] && entries_[size_t(end)].first == entries_[size_t(j)].first)
          ++end;
        if (!visit(Edge(int(a), entries_[size_t(j)].first),
                   std::span<const int>(users_.data() + j, size_t(end - j))))
          return;
        j = end;
      }
  }

 private:
  std::vector<int> start_;                    // per smaller point: its entries
  std::vector<std::pair<int, int>> entries_;  // (larger point, triangle), sorted
  std::vector<int> users_;                    // the entries' triangles
};

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

void manifold(const EdgeTable& edges, SurfaceCheck& out, size_t max_problems) {
  edges.for_each([&](Edge edge, std::span<const int> users) {
    if (out.problems.size() >= max_problems) return false;
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
    return true;
  });
}

// Flips triangles so that each edge is run once each way (breadth first from triangle 0 of
// each connected piece). Returns the flipped count, or -1 when no orientation fits (a
// one-sided surface).
long orient(std::vector<Triangle>& t, const EdgeTable& edges) {
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
        for (int other : edges.users(edge_of(a, b))) {
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

// Whether segment p q crosses triangle (a, b, c), of normal n = (b - a) x (c - a), at a point
// inside both (not at an end); dp, dq: n . (p - a) and n . (q - a).
bool segment_crosses(const Vec3& p, const Vec3& q, double dp, double dq, const Vec3& a,
                     const Vec3& b, const Vec3& c, const Vec3& n) {
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

// Each triangle's normal (b - a) x (c - a), centroid, and distance from it to its farthest
// corner: every point of the triangle lies within that distance of the centroid.
struct Shapes {
  std::vector<Vec3> normal, centroid;
  std::vector<double> reach;
};

Shapes shapes_of(const Mesh& mesh, const std::vector<Triangle>& t) {
  Shapes s;
  s.normal.resize(t.size()), s.centroid.resize(t.size()), s.reach.resize(t.size());
  for (size_t k = 0; k < t.size(); ++k) {
    const Vec3 &a = mesh.points[t[k][0]], &b = mesh.points[t[k][1]], &c = mesh.points[t[k][2]];
    s.normal[k] = (b - a).cross(c - a);
    s.centroid[k] = (a + b + c) / 3.0;
    for (int i : t[k]) s.reach[k] = std::max(s.reach[k], (mesh.points[i] - s.centroid[k]).norm());
  }
  return s;
}

bool triangles_cross(const Mesh& mesh, const Triangle& s, const Triangle& t, const Vec3& ns,
                     const Vec3& nt) {
  const auto& x = mesh.points;
  double ds[3], dt[3];  // s's corners against t's plane, t's against s's
  for (int e = 0; e < 3; ++e) {
    ds[e] = nt.dot(x[s[e]] - x[t[0]]);
    dt[e] = ns.dot(x[t[e]] - x[s[0]]);
  }
  for (int e = 0; e < 3; ++e) {
    const int f = (e + 1) % 3;
    if (segment_crosses(x[s[e]], x[s[f]], ds[e], ds[f], x[t[0]], x[t[1]], x[t[2]], nt)) return true;
    if (segment_crosses(x[t[e]], x[t[f]], dt[e], dt[f], x[s[0]], x[s[1]], x[s[2]], ns)) return true;
  }
  return false;
}

// The triangles' centroids and reaches in the hash's order, and the runs of that order filed
// around one cell: the triangles of that cell (often consecutive in a file) scan them in place.
struct Near {
  std::vector<int> index;
  std::vector<double> x, y, z, reach;
  TriangleHash::Cell cell{INT64_MIN, 0, 0};
  std::vector<std::pair<int, int>> runs;
  std::vector<int> hits;  // of one scan: positions that may meet

  Near(const TriangleHash& hash, const Shapes& shape) {
    index.assign(hash.entries().begin(), hash.entries().end());
    for (int o : index) {
      const Vec3& p = shape.centroid[size_t(o)];
      x.push_back(p.x()), y.push_back(p.y()), z.push_back(p.z());
      reach.push_back(shape.reach[size_t(o)]);
    }
  }
  void gather(TriangleHash& hash, const TriangleHash::Cell& c) {
    cell = c;
    runs.clear();
    size_t size = 0;
    hash.runs_around(c, [&](int first, int last) {
      runs.emplace_back(first, last);
      size += size_t(last - first);
    });
    hits.resize(size);
  }
  // Positions of the triangles after k whose centroid is within their reach and k's of k's
  // centroid (a relative margin far above rounding keeps every pair that might touch).
  size_t scan(int k, const Vec3& p, double r) {
    size_t count = 0;
    for (const auto& [first, last] : runs) {
      // The run's entries are in triangle order: those after k are its tail.
      const int from =
          int(std::upper_bound(index.begin() + first, index.begin() + last, k) - index.begin());
      for (int j = from; j < last; ++j) {
        const double dx = x[size_t(j)] - p.x(), dy = y[size_t(j)] - p.y(),
                     dz = z[size_t(j)] - p.z(), apart = r + reach[size_t(j)];
        hits[count] = j;
        count += size_t(dx * dx + dy * dy + dz * dz <= 1.0001 * apart * apart);
      }
    }
    return count;
  }
};

// Triangles sharing no point whose edges cross the other (a spatial hash finds the pairs
// near enough to meet; those whose centroids are farther apart than their reaches cannot).
void self_intersections(const Mesh& mesh, const std::vector<Triangle>& t, SurfaceCheck& out,
                        size_t max_problems) {
  const Shapes shape = shapes_of(mesh, t);
  const double reach = *std::max_element(shape.reach.begin(), shape.reach.end());
  TriangleHash hash;
  hash.reserve(t.size());
  hash.build(t, mesh.points, reach);  // cells of 2 reach: meeting triangles are neighbours
  Near near(hash, shape);
  for (size_t k = 0; k < t.size() && out.problems.size() < max_problems; ++k) {
    const TriangleHash::Cell cell = hash.cell_of(shape.centroid[k]);
    if (cell != near.cell) near.gather(hash, cell);
    const size_t hits = near.scan(int(k), shape.centroid[k], shape.reach[k]);
    for (size_t h = 0; h < hits && out.problems.size() < max_problems; ++h) {
      const size_t o = size_t(near.index[size_t(near.hits[h])]);
      if (share_point(t[k], t[o])) continue;
      if (triangles_cross(mesh, t[k], t[o], shape.normal[k], shape.normal[o]))
        out.problems.push_back(fmt::format("triangles {} and {} intersect", k, o));
    }
  }
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
  const EdgeTable edges(t);
  manifold(edges, out, max_problems);
  if (!out.problems.empty()) return out;
  const std::vector<Triangle> given = t;
  const long flipped = orient(t, edges);
  if (flipped < 0) {
    out.problems.emplace_back("no orientation fits every triangle: the surface is one-sided");
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
    out.repairs.emplace_back("every triangle flipped: the surface was inside out (normals inward)");
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
