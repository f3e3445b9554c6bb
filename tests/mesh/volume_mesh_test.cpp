// Closed surfaces checked, repaired and filled with tetrahedra (Gmsh), against the volume the
// surface encloses.
#include <gtest/gtest.h>

#include "mesh/surface_check.hpp"
#include "phymul/meshing.hpp"

namespace phymul {
namespace {

double enclosed(const Mesh& m) {
  double six = 0.0;
  for (const Cell& c : m.cells)
    six += m.points[size_t(c.nodes[0])].dot(
        m.points[size_t(c.nodes[1])].cross(m.points[size_t(c.nodes[2])]));
  return six / 6.0;
}

TEST(SurfaceCheck, AnEllipsoidIsClosedAndAnInsideOutOneIsTurnedOutward) {
  Mesh m = make_ellipsoid_surface(Vec3(0.02, 0.015, 0.01), 2);
  EXPECT_TRUE(check_closed_surface(m).problems.empty());
  const double volume = enclosed(m);
  // Outward (positive), and inscribed in the ellipsoid: a little less than its volume.
  const double ellipsoid = 4.0 / 3.0 * M_PI * 0.02 * 0.015 * 0.01;
  EXPECT_LT(volume, ellipsoid);
  EXPECT_GT(volume, 0.95 * ellipsoid);
  for (Cell& c : m.cells) std::swap(c.nodes[1], c.nodes[2]);
  const SurfaceCheck check = check_closed_surface(m);
  ASSERT_TRUE(check.problems.empty());
  ASSERT_EQ(check.repairs.size(), 1u);
  EXPECT_NE(check.repairs[0].find("inside out"), std::string::npos);
  EXPECT_DOUBLE_EQ(enclosed(m), volume);
}

TEST(SurfaceCheck, AMissingTriangleOpensTheSurfaceAtItsThreeEdges) {
  Mesh m = make_ellipsoid_surface(Vec3(0.02, 0.02, 0.02), 1);
  const Cell gone = m.cells.front();
  m.cells.erase(m.cells.begin());
  const SurfaceCheck check = check_closed_surface(m);
  ASSERT_EQ(check.problems.size(), 3u);
  for (const std::string& p : check.problems) EXPECT_NE(p.find("is not closed"), std::string::npos);
  EXPECT_NE(check.problems[0].find(std::to_string(std::min(gone.nodes[0], gone.nodes[1]))),
            std::string::npos);
}

TEST(VolumeMesh, TetrahedraFillExactlyWhatTheSurfaceEncloses) {
  const Mesh surface = make_ellipsoid_surface(Vec3(0.02, 0.015, 0.015), 3);
  const Mesh volume = fill_with_tetrahedra(surface, 0.004);
  ASSERT_GT(volume.points.size(), surface.points.size());
  for (size_t i = 0; i < surface.points.size(); ++i)
    ASSERT_EQ(volume.points[i], surface.points[i]) << "surface point " << i << " moved";
  double total = 0.0;
  for (const Cell& c : volume.cells) {
    ASSERT_EQ(c.type, CellType::tetra);
    const double v = cell_measure(volume.points, c);
    ASSERT_GT(v, 0.0);
    total += v;
  }
  EXPECT_NEAR(total, enclosed(surface), 1e-12 * enclosed(surface));
  const TetraQuality q = tetra_quality(volume);
  EXPECT_EQ(q.tetrahedra, volume.cells.size());
  EXPECT_GT(q.min_dihedral_deg, 5.0);
  EXPECT_LT(q.max_radius_edge, 3.0);
  EXPECT_THROW(fill_with_tetrahedra(surface, -1.0), MeshError);
}

}  // namespace
}  // namespace phymul
