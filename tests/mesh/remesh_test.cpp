// Isotropic remeshing of an irregular, over-fine sphere, against the analytic sphere.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>

#include "mesh/surface_check.hpp"
#include "phymul/meshing.hpp"

namespace phymul {
namespace {

constexpr double kRadius = 0.02;  // m

Cell triangle(int a, int b, int c) {
  Cell t;
  t.type = CellType::triangle;
  t.nodes[0] = a, t.nodes[1] = b, t.nodes[2] = c;
  return t;
}

// One conforming refinement: the edges whose midpoint lies above z = 0 are split (at the
// sphere), each triangle cut by how many of its edges were (1, 2 or 3), so the upper half
// gets finer and the band between the halves gets obtuse triangles.
void refine_upper(Mesh& m) {
  std::map<std::pair<int, int>, int> middle;
  auto mid = [&](int a, int b) {
    const Vec3 p = (m.points[size_t(a)] + m.points[size_t(b)]) / 2.0;
    if (p.z() <= 0.0) return -1;
    const auto key = std::minmax(a, b);
    auto [it, fresh] = middle.try_emplace({key.first, key.second}, int(m.points.size()));
    if (fresh) m.points.push_back(p.normalized() * kRadius);
    return it->second;
  };
  std::vector<Cell> cells;
  for (const Cell& c : m.cells) {
    std::array<int, 3> v{c.nodes[0], c.nodes[1], c.nodes[2]}, s{};
    for (size_t k = 0; k < 3; ++k) s[k] = mid(v[k], v[(k + 1) % 3]);
    const int split = int(s[0] >= 0) + int(s[1] >= 0) + int(s[2] >= 0);
    // Rotate so that the split edges come first: v0 v1 (s0), then v1 v2 (s1).
    for (int r = 0; r < 3 && split < 3 && split > 0; ++r) {
      if (s[0] >= 0 && (split == 1 || s[1] >= 0)) break;
      std::rotate(v.begin(), v.begin() + 1, v.end());
      std::rotate(s.begin(), s.begin() + 1, s.end());
    }
    if (split == 0) {
      cells.push_back(c);
    } else if (split == 1) {
      cells.push_back(triangle(v[0], s[0], v[2]));
      cells.push_back(triangle(s[0], v[1], v[2]));
    } else if (split == 2) {
      cells.push_back(triangle(s[0], v[1], s[1]));
      cells.push_back(triangle(v[0], s[0], s[1]));
      cells.push_back(triangle(v[0], s[1], v[2]));
    } else {
      cells.push_back(triangle(v[0], s[0], s[2]));
      cells.push_back(triangle(s[0], v[1], s[1]));
      cells.push_back(triangle(s[2], s[1], v[2]));
      cells.push_back(triangle(s[0], s[1], s[2]));
    }
  }
  m.cells = std::move(cells);
}

// A segmentation-like sphere: an icosphere (edges ~2.6 mm) refined twice more above z = 0
// (~0.7 mm), every point then jittered along the sphere by ~0.04 mm; all points on the sphere.
Mesh irregular_sphere() {
  Mesh m = make_ellipsoid_surface(Vec3::Constant(kRadius), 3);
  refine_upper(m);
  refine_upper(m);
  std::mt19937 random(7);
  std::normal_distribution<double> jitter(0.0, 0.04e-3);
  for (Vec3& p : m.points) {
    const Vec3 n = p.normalized(), t(jitter(random), jitter(random), jitter(random));
    p = (p + t - t.dot(n) * n).normalized() * kRadius;
  }
  return m;
}

TEST(Remesh, TheIrregularSphereIsClosed) {
  Mesh m = irregular_sphere();
  EXPECT_TRUE(check_closed_surface(m).problems.empty());
}

// Largest circumradius of the triangles: their planes lie at least sqrt(R^2 - rc^2) from the
// centre when their corners are on the sphere.
double largest_circumradius(const Mesh& m) {
  double largest = 0.0;
  for (const Cell& c : m.cells) {
    const Vec3 a = m.points[size_t(c.nodes[0])], b = m.points[size_t(c.nodes[1])],
               d = m.points[size_t(c.nodes[2])];
    const double area2 = (b - a).cross(d - a).norm();
    largest = std::max(largest, (b - a).norm() * (d - b).norm() * (a - d).norm() / (2.0 * area2));
  }
  return largest;
}

TEST(Remesh, AnIrregularFineSphereBecomesEvenTrianglesOnIt) {
  const Mesh input = irregular_sphere();
  const double edge = 0.004;
  const Remeshed r = remesh_surface(input, edge);
  Mesh out = r.surface;
  const SurfaceCheck check = check_closed_surface(out);
  EXPECT_TRUE(check.problems.empty());
  EXPECT_TRUE(check.repairs.empty());  // outward already
  const SurfaceQuality in = surface_quality(input), q = r.quality;
  std::printf("input: %zu triangles, min angle %.1f, aspect %.2f, edges %.2f/%.2f/%.2f mm\n",
              in.triangles, in.min_angle_deg, in.max_aspect, in.edge_min * 1e3, in.edge_mean * 1e3,
              in.edge_max * 1e3);
  std::printf(
      "output: %zu triangles, min angle %.1f, aspect %.2f, edges %.2f/%.2f/%.2f mm, "
      "deviation %.3f mm, volume %.4g -> %.4g\n",
      q.triangles, q.min_angle_deg, q.max_aspect, q.edge_min * 1e3, q.edge_mean * 1e3,
      q.edge_max * 1e3, r.deviation * 1e3, r.volume_before, r.volume_after);
  EXPECT_NEAR(q.edge_mean, edge, 0.2 * edge);
  EXPECT_LE(q.edge_max, 4.0 / 3.0 * edge);  // the split threshold
  EXPECT_GT(q.min_angle_deg, 30.0);
  EXPECT_LT(q.max_aspect, 2.0);
  // Inscribed triangles of edge L miss a mean depth L^2 / (8R) of the sphere (a paraboloid
  // cap over an equilateral triangle), a volume fraction 3 L^2 / (8 R^2): with every edge at
  // most 4/3 of the target, less than 2/3 (edge / R)^2 (2.7% here).
  const double sphere = 4.0 / 3.0 * M_PI * std::pow(kRadius, 3);
  EXPECT_LT(r.volume_after, sphere);
  EXPECT_GT(r.volume_after, sphere * (1.0 - 2.0 / 3.0 * std::pow(edge / kRadius, 2)));
  EXPECT_NEAR(enclosed_volume(input), r.volume_before, 1e-15);
  // Every point on the input: between the sphere and the input triangles' planes.
  const double inner = std::sqrt(kRadius * kRadius - std::pow(largest_circumradius(input), 2));
  for (const Vec3& p : out.points) {
    EXPECT_LE(p.norm(), kRadius + 1e-12);
    EXPECT_GE(p.norm(), inner - 1e-12);
  }
  // Between the two surfaces: at most the output's chord depth plus the input's.
  const double chord =
      kRadius - std::sqrt(kRadius * kRadius - std::pow(largest_circumradius(out), 2));
  EXPECT_LE(r.deviation, chord + (kRadius - inner));
  EXPECT_GT(r.deviation, 0.5 * chord);
}

TEST(Remesh, AnEdgeLongerThanTheObjectIsRefusedWithItsRange) {
  const Mesh input = make_ellipsoid_surface(Vec3::Constant(kRadius), 2);
  try {
    remesh_surface(input, 0.05);
    FAIL() << "no MeshError";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("the edge must be in"), std::string::npos) << e.what();
  }
  EXPECT_THROW(remesh_surface(input, 0.0), MeshError);
  EXPECT_THROW(remesh_surface(input, NAN), MeshError);
  Mesh open = input;
  open.cells.pop_back();
  EXPECT_THROW(remesh_surface(open, 0.004), MeshError);
  Mesh inside_out = input;
  for (Cell& c : inside_out.cells) std::swap(c.nodes[1], c.nodes[2]);
  EXPECT_THROW(remesh_surface(inside_out, 0.004), MeshError);
}

}  // namespace
}  // namespace phymul
