// Edge flips on a closed triangle surface: the diagonal of two triangles turned when that
// improves the worse of the two, on nearly flat pairs only (the shape stays).
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "mesh/surface_smoothing.hpp"

namespace phymul::detail {
namespace {

std::uint64_t key(int a, int b) {
  return (std::uint64_t(std::uint32_t(std::min(a, b))) << 32) | std::uint32_t(std::max(a, b));
}

Vec3 area_normal(const Mesh& m, int a, int b, int c) {
  const Vec3& p = m.points[size_t(a)];
  return (m.points[size_t(b)] - p).cross(m.points[size_t(c)] - p);
}

// The edge of triangle t from a to b, and the corner opposite it.
int opposite(const Cell& t, int a, int b) {
  for (int k = 0; k < 3; ++k)
    if (t.nodes[size_t(k)] != a && t.nodes[size_t(k)] != b) return t.nodes[size_t(k)];
  return -1;
}

}  // namespace

double triangle_quality(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double sum = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  return sum > 0.0 ? 2.0 * std::sqrt(3.0) * (b - a).cross(c - a).norm() / sum : 0.0;
}

int flip_edges(Mesh& m, int passes) {
  std::unordered_map<std::uint64_t, std::array<int, 2>> edges;
  for (size_t t = 0; t < m.cells.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      auto [it, added] =
          edges.try_emplace(key(m.cells[t].nodes[size_t(k)], m.cells[t].nodes[size_t((k + 1) % 3)]),
                            std::array<int, 2>{int(t), -1});
      if (!added) it->second[1] = int(t);
    }
  auto q = [&](int a, int b, int c) {
    return triangle_quality(m.points[size_t(a)], m.points[size_t(b)], m.points[size_t(c)]);
  };
  int flipped = 0;
  for (int pass = 0; pass < passes; ++pass) {
    int now = 0;
    for (size_t t1 = 0; t1 < m.cells.size(); ++t1)
      for (int k = 0; k < 3; ++k) {
        const int a = m.cells[t1].nodes[size_t(k)], b = m.cells[t1].nodes[size_t((k + 1) % 3)];
        const auto pair = edges.at(key(a, b));
        const int t2 = pair[0] == int(t1) ? pair[1] : pair[0];
        if (t2 < 0) continue;
        const int c = opposite(m.cells[t1], a, b), d = opposite(m.cells[size_t(t2)], a, b);
        if (c == d || edges.contains(key(c, d))) continue;
        const Vec3 n1 = area_normal(m, a, b, c), n2 = area_normal(m, b, a, d);
        if (n1.dot(n2) < 0.95 * n1.norm() * n2.norm()) continue;  // a crease: keep it
        if (std::min(q(c, a, d), q(d, b, c)) <= 1.05 * std::min(q(a, b, c), q(b, a, d))) continue;
        const Vec3 m1 = area_normal(m, c, a, d), m2 = area_normal(m, d, b, c);
        if (m1.dot(n1 + n2) <= 0.0 || m2.dot(n1 + n2) <= 0.0) continue;  // would fold over
        // (a, b, c), (b, a, d) -> (c, a, d), (d, b, c): edge a-d moves to t1, b-c to t2.
        m.cells[t1].nodes = {c, a, d, -1, -1, -1, -1, -1};
        m.cells[size_t(t2)].nodes = {d, b, c, -1, -1, -1, -1, -1};
        edges.erase(key(a, b));
        edges[key(c, d)] = {int(t1), t2};
        for (int& t : edges.at(key(a, d))) t = t == t2 ? int(t1) : t;
        for (int& t : edges.at(key(b, c))) t = t == int(t1) ? t2 : t;
        ++now;
        break;  // t1 changed: its other edges next pass
      }
    flipped += now;
    if (now == 0) break;
  }
  return flipped;
}

}  // namespace phymul::detail
