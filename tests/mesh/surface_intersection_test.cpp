// The self-intersection check's spatial pruning against all pairs: two overlapping spheres
// (one closed surface of two parts) cross along a curve; every crossing pair the check
// reports is one an all-pairs search with its own segment-triangle test (Moller-Trumbore)
// finds, and the other way round.
#include <gtest/gtest.h>

#include <cstdio>
#include <set>
#include <utility>

#include "mesh/surface_check.hpp"
#include "phymul/mesh.hpp"

namespace phymul {
namespace {

// Whether segment p q passes through the inside of triangle (a, b, c), away from its ends.
bool segment_hits(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 d = q - p, e1 = b - a, e2 = c - a, h = d.cross(e2);
  const double det = e1.dot(h);
  if (std::abs(det) < 1e-30) return false;  // parallel: generic positions never cross so
  const Vec3 s = p - a;
  const double u = s.dot(h) / det;
  const Vec3 qv = s.cross(e1);
  const double v = d.dot(qv) / det, t = e2.dot(qv) / det;
  return u > 0.0 && v > 0.0 && u + v < 1.0 && t > 0.0 && t < 1.0;
}

std::set<std::pair<int, int>> all_pairs(const Mesh& m) {
  std::set<std::pair<int, int>> found;
  const auto& x = m.points;
  for (size_t k = 0; k < m.cells.size(); ++k)
    for (size_t o = k + 1; o < m.cells.size(); ++o) {
      const auto& s = m.cells[k].nodes;
      const auto& t = m.cells[o].nodes;
      bool shared = false;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) shared |= s[size_t(i)] == t[size_t(j)];
      if (shared) continue;
      bool cross = false;
      for (int e = 0; e < 3 && !cross; ++e) {
        const int f = (e + 1) % 3;
        cross = segment_hits(x[s[e]], x[s[f]], x[t[0]], x[t[1]], x[t[2]]) ||
                segment_hits(x[t[e]], x[t[f]], x[s[0]], x[s[1]], x[s[2]]);
      }
      if (cross) found.insert({int(k), int(o)});
    }
  return found;
}

TEST(SurfaceCheck, TheCrossingTrianglesAreThoseAnAllPairsSearchFinds) {
  for (const Vec3& offset : {Vec3(0.011, 0.0031, 0.0017), Vec3(0.004, -0.0093, 0.0061)}) {
    Mesh m = make_ellipsoid_surface(Vec3(0.010, 0.008, 0.007), 3);
    const Mesh other = make_ellipsoid_surface(Vec3(0.009, 0.010, 0.006), 3, offset);
    const int base = int(m.points.size());
    m.points.insert(m.points.end(), other.points.begin(), other.points.end());
    for (Cell c : other.cells) {
      for (int i = 0; i < 3; ++i) c.nodes[size_t(i)] += base;
      m.cells.push_back(c);
    }
    const std::set<std::pair<int, int>> expected = all_pairs(m);
    ASSERT_GT(expected.size(), 20u);
    const SurfaceCheck check = check_closed_surface(m, 1000000);
    std::set<std::pair<int, int>> reported;
    for (const std::string& p : check.problems) {
      int k = -1, o = -1;
      ASSERT_EQ(std::sscanf(p.c_str(), "triangles %d and %d intersect", &k, &o), 2) << p;
      reported.insert({k, o});
    }
    EXPECT_EQ(reported, expected);
    std::printf("%zu crossing pairs among %zu triangles\n", expected.size(), m.cells.size());
  }
}

}  // namespace
}  // namespace phymul
