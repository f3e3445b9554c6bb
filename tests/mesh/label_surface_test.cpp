// Label images to closed surfaces: the slices' signed distances, marching tetrahedra, and
// the whole path on voxelised ellipsoids in oblique frames against their analytic volume.
#include "phymul/label_surface.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "mesh/distance_2d.hpp"
#include "mesh/marching_tetrahedra.hpp"
#include "mesh/surface_check.hpp"
#include "phymul/meshing.hpp"

namespace phymul {
namespace {

TEST(SignedDistance2d, ADiscsDistanceIsItsRadiusLessTheDistanceToItsCentre) {
  const int n = 80;
  const double s = 0.5, r = 12.0, c = 20.1;  // mm
  std::vector<unsigned char> disc(size_t(n * n));
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a) disc[size_t(a + n * b)] = std::hypot(a * s - c, b * s - c) <= r;
  const std::vector<float> d = detail::signed_distance_2d(disc, n, n, s, s, 100.0);
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a) {
      const double exact = std::hypot(a * s - c, b * s - c) - r;
      // The pixels' boundary is a staircase of half a pixel's depth about the circle.
      EXPECT_NEAR(d[size_t(a + n * b)], exact, 0.75 * s) << a << ", " << b;
    }
  EXPECT_EQ(detail::signed_distance_2d(std::vector<unsigned char>(9, 0), 3, 3, s, s, 4.0),
            std::vector<float>(9, 4.0f));
}

TEST(MarchingTetrahedra, ASphereIsClosedOutwardAndEnclosesItsVolume) {
  detail::ScalarGrid g;
  g.nodes = {21, 23, 25};
  g.spacing = Vec3(1.0, 1.1, 0.9);
  const Vec3 centre(10.3, 12.1, 10.7);
  const double r = 7.0;
  for (int z = 0; z < g.nodes[2]; ++z)
    for (int y = 0; y < g.nodes[1]; ++y)
      for (int x = 0; x < g.nodes[0]; ++x) {
        const double f = (Vec3(x, y, z).cwiseProduct(g.spacing) - centre).norm() - r;
        g.values.push_back(float(std::abs(f) < 1e-3 ? 1e-3 : f));
      }
  Mesh m = detail::marching_tetrahedra(g);
  ASSERT_TRUE(is_closed(boundary_triangles(m)));
  const SurfaceCheck check = check_closed_surface(m);
  EXPECT_TRUE(check.problems.empty());
  EXPECT_TRUE(check.repairs.empty());  // already outward
  // Inscribed chords on a ~1 mm grid: within 2 % of the sphere's volume, below it.
  const double volume = enclosed_volume(m.points, boundary_triangles(m));
  EXPECT_NEAR(volume, 4.0 / 3.0 * M_PI * r * r * r, 0.02 * 4.0 / 3.0 * M_PI * r * r * r);
}

// An ellipsoid's voxels (semi-axes along the grid's axes), the grid rotated and moved.
struct Ellipsoid {
  LabelImage image;
  Vec3 semi, centre;  // m, centre in the physical frame
  Eigen::Matrix3d rotation;
};

Ellipsoid voxelised(const Vec3& voxel, const Vec3& semi) {
  Ellipsoid e;
  e.semi = semi;
  e.rotation = Eigen::AngleAxisd(0.6, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  LabelImage& im = e.image;
  im.dims = {70, 60, 18};
  im.axes = e.rotation * voxel.asDiagonal();
  im.origin = Vec3(-0.04, 0.025, 0.06);
  const Vec3 centre_ijk(33.3, 29.6, 8.4);
  e.centre = im.origin + im.axes * centre_ijk;
  for (int k = 0; k < im.dims[2]; ++k)
    for (int j = 0; j < im.dims[1]; ++j)
      for (int i = 0; i < im.dims[0]; ++i) {
        const Vec3 local = (Vec3(i, j, k) - centre_ijk).cwiseProduct(voxel);
        im.labels.push_back(local.cwiseQuotient(semi).squaredNorm() <= 1.0 ? 2 : 0);
      }
  return e;
}

TEST(LabelSurface, AnEllipsoidOfThickSlicesInAnObliqueFrameKeepsItsVolumeAndCentre) {
  const Vec3 semi(0.020, 0.015, 0.017);
  const Ellipsoid e = voxelised(Vec3(0.6e-3, 0.6e-3, 4e-3), semi);
  const int labels[] = {2};
  LabelSurfaceReport r;
  Mesh m = label_surface(e.image, labels, 3e-3, &r);
  EXPECT_TRUE(check_closed_surface(m).problems.empty());
  const double exact = 4.0 / 3.0 * M_PI * semi.prod();
  EXPECT_NEAR(r.labelled_volume, exact, 0.02 * exact);  // the voxels' own estimate
  EXPECT_NEAR(r.surface_volume, exact, 0.02 * exact);
  EXPECT_DOUBLE_EQ(r.surface_volume, enclosed_volume(m.points, boundary_triangles(m)));
  EXPECT_LT((r.centroid - e.centre).norm(), 0.2 * 0.6e-3);  // a fifth of the in-plane voxel
  EXPECT_EQ(r.slice_axis, 2);
  EXPECT_EQ(r.dropped_components, 0);
  // The triangles come out about the asked edge (3 mm), not the grid's 0.6 mm voxels.
  double sum = 0.0;
  for (const Cell& c : m.cells)
    sum += (m.points[size_t(c.nodes[0])] - m.points[size_t(c.nodes[1])]).norm();
  EXPECT_GT(sum / double(m.cells.size()), 0.6 * 3e-3);
  EXPECT_LT(sum / double(m.cells.size()), 1.3 * 3e-3);
  // Every point near the ellipsoid: within a quarter slice (the poles) along its ray.
  for (const Vec3& p : m.points) {
    const Vec3 q = e.rotation.transpose() * (p - e.centre);
    const double rho = q.cwiseQuotient(semi).norm();
    EXPECT_LT(std::abs(q.norm() * (1.0 - 1.0 / rho)), 1e-3) << p.transpose();
  }
}

TEST(LabelSurface, TheThickAxisIsFoundWhereverItIs) {
  // The same ellipsoid with its slices across i: the axis is found, the volume kept.
  const Vec3 semi(0.017, 0.015, 0.020);
  Ellipsoid e = voxelised(Vec3(4e-3, 0.6e-3, 0.6e-3), semi);
  e.image.dims = {18, 60, 70};
  const Vec3 centre_ijk(8.4, 29.6, 33.3);
  e.image.labels.clear();
  for (int k = 0; k < 70; ++k)
    for (int j = 0; j < 60; ++j)
      for (int i = 0; i < 18; ++i) {
        const Vec3 local = (Vec3(i, j, k) - centre_ijk).cwiseProduct(Vec3(4e-3, 0.6e-3, 0.6e-3));
        e.image.labels.push_back(local.cwiseQuotient(semi).squaredNorm() <= 1.0 ? 2 : 0);
      }
  const int labels[] = {2};
  LabelSurfaceReport r;
  label_surface(e.image, labels, 3e-3, &r);
  EXPECT_EQ(r.slice_axis, 0);
  EXPECT_NEAR(r.surface_volume, 4.0 / 3.0 * M_PI * semi.prod(),
              0.02 * 4.0 / 3.0 * M_PI * semi.prod());
}

TEST(LabelSurface, IslandsAndCavitiesAreLeftOutAndCounted) {
  LabelImage im;
  im.dims = {40, 40, 40};
  im.axes = Eigen::Matrix3d::Identity() * 1e-3;
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) {
        const double r = (Vec3(i, j, k) - Vec3(18, 18, 18)).norm();
        const double island = (Vec3(i, j, k) - Vec3(34, 34, 34)).norm();
        im.labels.push_back((r <= 12.0 && r > 4.0) || island <= 2.5 ? 1 : 0);
      }
  const int labels[] = {1};
  LabelSurfaceReport r;
  const Mesh m = label_surface(im, labels, 2e-3, &r);
  EXPECT_EQ(r.dropped_components, 2);  // the island and the cavity
  // The outer ball alone (voxel centres within 12 mm), its cavity not taken off.
  const double ball = 4.0 / 3.0 * M_PI * std::pow(12e-3, 3);
  EXPECT_NEAR(r.surface_volume, ball, 0.03 * ball);
  EXPECT_GT(r.dropped_volume, 0.0);
}

// Speckled labels (voxel-wide parts, touching corners) in random oblique frames: before the
// fallback to less smoothing, 4 in 10 such surfaces folded and 1 in 10 fills failed (1,500
// images).
TEST(LabelSurface, SpeckledLabelsAlwaysGiveAClosedSurfaceThatFills) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int meshed = 0;
  for (int t = 0; t < 30; ++t) {
    LabelImage im;
    im.dims = {3 + int(rng() % 10), 3 + int(rng() % 10), 2 + int(rng() % 6)};
    const Vec3 s(0.3e-3 + 2e-3 * u(rng), 0.3e-3 + 2e-3 * u(rng), 0.5e-3 + 5e-3 * u(rng));
    const Vec3 axis = Vec3(u(rng), u(rng), u(rng) + 0.1).normalized();
    im.axes = Eigen::AngleAxisd(6.0 * u(rng), axis).toRotationMatrix() * s.asDiagonal();
    const double density = u(rng);
    for (int v = 0; v < im.dims[0] * im.dims[1] * im.dims[2]; ++v)
      im.labels.push_back(u(rng) < density ? 1 : 0);
    const int labels[] = {1};
    const double edge = s.maxCoeff() * (0.3 + 3.0 * u(rng));
    try {
      Mesh surface;
      LabelSurfaceReport r;
      const Mesh volume = label_volume(im, labels, edge, &r, &surface);
      EXPECT_TRUE(check_closed_surface(surface).problems.empty()) << t;
      for (const Cell& c : volume.cells) EXPECT_GT(cell_measure(volume.points, c), 0.0) << t;
      ++meshed;
    } catch (const MeshError& e) {  // only an empty image or too coarse an edge
      const std::string what = e.what();
      EXPECT_TRUE(what.find("no voxel") != std::string::npos ||
                  what.find("too small") != std::string::npos)
          << t << ": " << what;
    }
  }
  EXPECT_GE(meshed, 18);
}

TEST(LabelSurface, NoVoxelOfTheLabelsNamesTheLabelsPresent) {
  const Ellipsoid e = voxelised(Vec3(1e-3, 1e-3, 2e-3), Vec3(0.01, 0.01, 0.01));
  const int labels[] = {1, 3};
  try {
    label_surface(e.image, labels, 3e-3);
    FAIL() << "no error";
  } catch (const MeshError& error) {
    EXPECT_NE(std::string(error.what()).find("no voxel holds label 1 or 3: the image holds 0 ("),
              std::string::npos)
        << error.what();
    EXPECT_NE(std::string(error.what()).find("), 2 ("), std::string::npos) << error.what();
  }
}

TEST(LabelSurface, AnEdgeTooSmallForTheRegionIsRefusedBeforeTheGridIsMade) {
  const Ellipsoid e = voxelised(Vec3(1e-3, 1e-3, 2e-3), Vec3(0.02, 0.02, 0.02));
  const int labels[] = {2};
  EXPECT_THROW(label_surface(e.image, labels, 1e-5), MeshError);
  EXPECT_THROW(label_surface(e.image, labels, std::nan("")), MeshError);
  EXPECT_THROW(label_surface(e.image, labels, -1.0), MeshError);
}

}  // namespace
}  // namespace phymul
