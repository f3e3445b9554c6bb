// The hexahedral ellipsoid and the wedge split that lets finite elements run on the shells.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "phymul/mesh.hpp"

namespace phymul {
namespace {

double total_volume(const Mesh& mesh) {
  double v = 0.0;
  for (const Cell& c : mesh.cells) v += cell_measure(mesh.points, c);
  return v;
}

TEST(EllipsoidHexa, SurfaceNodesLieOnTheEllipsoidAndTheVolumeConverges) {
  const Vec3 radii(0.02, 0.015, 0.015), centre(0.001, -0.002, 0.003);
  const double exact = 4.0 / 3.0 * std::numbers::pi * radii.prod();
  double previous_error = 1.0;
  for (int n : {4, 8, 16}) {
    const Mesh mesh = make_ellipsoid_hexa(radii, n, centre);
    EXPECT_NO_THROW(validate(mesh));  // no inverted or degenerate cell, corners included
    EXPECT_EQ(mesh.points.size(), size_t((n + 1) * (n + 1) * (n + 1)));
    for (int i : mesh.node_sets.at("surface"))
      EXPECT_NEAR((mesh.points[i] - centre).cwiseQuotient(radii).norm(), 1.0, 1e-12);
    EXPECT_EQ(mesh.points[mesh.node_sets.at("top")[0]], centre + Vec3(0, 0, radii.z()));
    EXPECT_EQ(mesh.points[mesh.node_sets.at("bottom")[0]], centre - Vec3(0, 0, radii.z()));
    // Flat faces inscribed in a curved surface: the volume falls short, less and less.
    const double error = (exact - total_volume(mesh)) / exact;
    EXPECT_GT(error, 0.0);
    EXPECT_LT(error, 0.6 * previous_error) << n;
    previous_error = error;
  }
  EXPECT_LT(previous_error, 0.01);
}

TEST(EllipsoidHexa, RejectsAnOddCount) {
  EXPECT_THROW(make_ellipsoid_hexa(Vec3::Constant(0.01), 5), std::invalid_argument);
}

TEST(WedgeTetrahedra, SplitsConformAndKeepTheVolume) {
  const Mesh shells = make_ellipsoid_volume(Vec3(0.02, 0.015, 0.015), 2, 3);
  std::map<std::array<int, 3>, int> faces;  // sorted triangle -> how many tetrahedra have it
  double wedges = 0.0, tetrahedra = 0.0;
  for (const Cell& c : shells.cells) {
    std::vector<Cell> parts{c};
    if (c.type == CellType::wedge) {
      wedges += cell_measure(shells.points, c);
      const auto split = wedge_tetrahedra(c);
      parts.assign(split.begin(), split.end());
      for (const Cell& t : parts) tetrahedra += std::abs(cell_measure(shells.points, t));
    }
    for (const Cell& t : parts)
      for (int skip = 0; skip < 4; ++skip) {
        std::array<int, 3> f{};
        for (int a = 0, k = 0; a < 4; ++a)
          if (a != skip) f[size_t(k++)] = t.nodes[size_t(a)];
        std::sort(f.begin(), f.end());
        ++faces[f];
      }
  }
  EXPECT_NEAR(tetrahedra, wedges, 1e-12 * wedges);
  // Conforming: an interior face is shared by exactly two tetrahedra, a boundary face is one
  // of the 320 surface triangles; a quad cut two ways would leave four faces used once.
  int boundary = 0;
  for (const auto& [f, count] : faces) {
    EXPECT_LE(count, 2);
    boundary += count == 1;
  }
  EXPECT_EQ(boundary, 320);
}

}  // namespace
}  // namespace phymul
