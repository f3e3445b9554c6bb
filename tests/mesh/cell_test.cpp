// Cell types, cell measures and validate().
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "mesh_test_util.hpp"
#include "phymul/mesh.hpp"

namespace phymul {
namespace {

using mesh_test::cell_of;
using mesh_test::contains;
using mesh_test::validation_error;

// Reference cells in VTK order, all positive.
std::vector<Vec3> unit_tetra_points() { return {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}; }

std::vector<Vec3> unit_cube_points() {
  return {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
}

std::vector<Vec3> unit_wedge_points() {
  return {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 1}, {1, 0, 1}};
}

Mesh single_cell_mesh(std::vector<Vec3> points, Cell cell) {
  Mesh mesh;
  mesh.points = std::move(points);
  mesh.cells = {cell};
  return mesh;
}

const Cell kTetra = cell_of(CellType::tetra, {0, 1, 2, 3});
const Cell kHexa = cell_of(CellType::hexa, {0, 1, 2, 3, 4, 5, 6, 7});
const Cell kWedge = cell_of(CellType::wedge, {0, 1, 2, 3, 4, 5});

TEST(MeshCellType, TablesFollowVtk) {
  EXPECT_EQ(node_count(CellType::triangle), 3);
  EXPECT_EQ(node_count(CellType::quad), 4);
  EXPECT_EQ(node_count(CellType::tetra), 4);
  EXPECT_EQ(node_count(CellType::hexa), 8);
  EXPECT_EQ(node_count(CellType::wedge), 6);
  EXPECT_EQ(vtk_cell_type(CellType::triangle), 5);
  EXPECT_EQ(vtk_cell_type(CellType::quad), 9);
  EXPECT_EQ(vtk_cell_type(CellType::tetra), 10);
  EXPECT_EQ(vtk_cell_type(CellType::hexa), 12);
  EXPECT_EQ(vtk_cell_type(CellType::wedge), 13);
  EXPECT_FALSE(is_volumetric(CellType::triangle));
  EXPECT_FALSE(is_volumetric(CellType::quad));
  EXPECT_TRUE(is_volumetric(CellType::tetra));
  EXPECT_TRUE(is_volumetric(CellType::hexa));
  EXPECT_TRUE(is_volumetric(CellType::wedge));
  EXPECT_STREQ(cell_type_name(CellType::hexa), "hexa");
  EXPECT_STREQ(cell_type_name(CellType::wedge), "wedge");
  EXPECT_EQ(kHexa.node_span().size(), 8u);
  EXPECT_THROW(node_count(CellType(42)), std::invalid_argument);
}

TEST(MeshCellMeasure, UnitTetraIsOneSixth) {
  EXPECT_NEAR(cell_measure(unit_tetra_points(), kTetra), 1.0 / 6.0, 1e-15);
}

TEST(MeshCellMeasure, UnitCubeHexaIsOne) {
  EXPECT_NEAR(cell_measure(unit_cube_points(), kHexa), 1.0, 1e-15);
}

TEST(MeshCellMeasure, ScaledAndShiftedHexaIsItsBoxVolume) {
  std::vector<Vec3> points = unit_cube_points();
  for (Vec3& p : points) p = Vec3(2.0, 3.0, 4.0).cwiseProduct(p) + Vec3(100.0, -50.0, 7.0);
  EXPECT_NEAR(cell_measure(points, kHexa), 24.0, 24.0 * 1e-13);
}

TEST(MeshCellMeasure, VtkWedgeIsHalf) {
  EXPECT_NEAR(cell_measure(unit_wedge_points(), kWedge), 0.5, 1e-15);
}

TEST(MeshCellMeasure, SurfaceCellsGiveTheirArea) {
  const std::vector<Vec3> points{{0, 0, 0}, {2, 0, 0}, {2, 3, 0}, {0, 3, 0}};
  EXPECT_NEAR(cell_measure(points, cell_of(CellType::triangle, {0, 1, 2})), 3.0, 1e-15);
  EXPECT_NEAR(cell_measure(points, cell_of(CellType::quad, {0, 1, 2, 3})), 6.0, 1e-15);
  // Area is positive whatever the orientation.
  EXPECT_NEAR(cell_measure(points, cell_of(CellType::quad, {0, 3, 2, 1})), 6.0, 1e-15);
}

TEST(MeshCellMeasure, WarpedHexaMatchesItsBoundaryTriangles) {
  std::vector<Vec3> points = unit_cube_points();
  points[6] += Vec3(0.1, -0.05, 0.3);  // warps the top, right and back faces
  points[3] += Vec3(0.0, 0.0, -0.2);   // and the bottom, left and back faces
  const Mesh mesh = single_cell_mesh(points, kHexa);
  const std::vector<Triangle> boundary = boundary_triangles(mesh);
  ASSERT_EQ(boundary.size(), 12u);
  EXPECT_TRUE(is_closed(boundary));
  EXPECT_NEAR(cell_measure(mesh.points, kHexa), enclosed_volume(mesh.points, boundary), 1e-15);
  EXPECT_NO_THROW(validate(mesh));
}

// Two hexas share a warped face but list it from different local corners; only a split that
// depends on the node ids alone makes their volumes add up to the enclosed volume.
TEST(MeshCellMeasure, SharedWarpedFaceSplitsIdenticallyFromBothSides) {
  Mesh mesh;
  for (int k = 0; k < 3; ++k) {
    for (const Vec3& p : std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}) {
      mesh.points.push_back(p + Vec3(0, 0, k));
    }
  }
  mesh.points[6].z() += 0.35;  // warps the shared middle face 4-5-6-7
  mesh.cells.push_back(cell_of(CellType::hexa, {0, 1, 2, 3, 4, 5, 6, 7}));
  // The upper hexa starts at node 5: its local diagonal 0-2 of the shared face is 5-7, the
  // lower one's is 4-6 (both cells still positive).
  mesh.cells.push_back(cell_of(CellType::hexa, {5, 6, 7, 4, 9, 10, 11, 8}));
  ASSERT_NO_THROW(validate(mesh));
  const std::vector<Triangle> boundary = boundary_triangles(mesh);
  EXPECT_EQ(boundary.size(), 20u);
  EXPECT_TRUE(is_closed(boundary));
  const double sum =
      cell_measure(mesh.points, mesh.cells[0]) + cell_measure(mesh.points, mesh.cells[1]);
  EXPECT_NEAR(sum, enclosed_volume(mesh.points, boundary), 1e-14);
  EXPECT_NEAR(sum, 2.0, 1e-14);  // the warp only moves volume from one hexa to the other
}

TEST(MeshValidate, AcceptsPositiveReferenceCells) {
  EXPECT_EQ(validation_error(single_cell_mesh(unit_tetra_points(), kTetra)), "");
  EXPECT_EQ(validation_error(single_cell_mesh(unit_cube_points(), kHexa)), "");
  EXPECT_EQ(validation_error(single_cell_mesh(unit_wedge_points(), kWedge)), "");
}

TEST(MeshValidate, RejectsInvertedTetra) {
  const std::string message = validation_error(
      single_cell_mesh(unit_tetra_points(), cell_of(CellType::tetra, {0, 2, 1, 3})));
  EXPECT_TRUE(contains(message, "cell 0 (tetra, nodes 0 2 1 3) is inverted"));
  EXPECT_TRUE(contains(message, "signed volume -0.167 m^3"));
}

TEST(MeshValidate, RejectsInvertedHexa) {
  const Cell upside_down = cell_of(CellType::hexa, {4, 5, 6, 7, 0, 1, 2, 3});
  const std::string message = validation_error(single_cell_mesh(unit_cube_points(), upside_down));
  EXPECT_TRUE(contains(message, "cell 0 (hexa, nodes 4 5 6 7 0 1 2 3) is inverted"));
  EXPECT_TRUE(contains(message, "signed volume -1 m^3"));
}

TEST(MeshValidate, RejectsInvertedWedge) {
  // The other orientation than VTK's: triangle 0-1-2 facing towards 3-4-5.
  const Cell flipped = cell_of(CellType::wedge, {0, 2, 1, 3, 5, 4});
  const std::string message = validation_error(single_cell_mesh(unit_wedge_points(), flipped));
  EXPECT_TRUE(contains(message, "cell 0 (wedge, nodes 0 2 1 3 5 4) is inverted"));
  EXPECT_TRUE(contains(message, "away from 3-4-5"));
}

TEST(MeshValidate, RejectsHexaFoldedAtACornerDespitePositiveVolume) {
  std::vector<Vec3> points = unit_cube_points();
  points[4] = Vec3(0.5, 0.5, -0.2);  // pulled through the bottom face
  const Mesh mesh = single_cell_mesh(points, kHexa);
  ASSERT_GT(cell_measure(mesh.points, kHexa), 0.0);
  const std::string message = validation_error(mesh);
  EXPECT_TRUE(contains(message, "is inverted at corner 0 (node 0)"));
}

TEST(MeshValidate, RejectsWedgeFoldedAtACornerDespitePositiveVolume) {
  std::vector<Vec3> points = unit_wedge_points();
  points[3] = Vec3(0.3, 0.3, -0.1);  // node 3 pulled under the triangle 0-1-2
  const Mesh mesh = single_cell_mesh(points, kWedge);
  ASSERT_GT(cell_measure(mesh.points, kWedge), 0.0);
  EXPECT_TRUE(contains(validation_error(mesh), "is inverted at corner 0"));
}

TEST(MeshValidate, RejectsDegenerateCells) {
  const std::vector<Vec3> flat{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1e-14}};
  EXPECT_TRUE(contains(validation_error(single_cell_mesh(flat, kTetra)),
                       "cell 0 (tetra, nodes 0 1 2 3) is degenerate: volume"));
  const std::vector<Vec3> line{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  EXPECT_TRUE(
      contains(validation_error(single_cell_mesh(line, cell_of(CellType::triangle, {0, 1, 2}))),
               "is degenerate: area 0 m^2"));
  std::vector<Vec3> squashed = unit_cube_points();
  for (int i = 4; i < 8; ++i) squashed[i].z() = 0.0;
  EXPECT_TRUE(contains(validation_error(single_cell_mesh(squashed, kHexa)), "is degenerate"));
}

TEST(MeshValidate, RejectsOutOfRangeNodes) {
  Mesh mesh = single_cell_mesh(unit_tetra_points(), cell_of(CellType::tetra, {0, 1, 2, 120}));
  EXPECT_TRUE(contains(validation_error(mesh),
                       "cell 0 (tetra, nodes 0 1 2 120) uses node 120 but the mesh has 4 nodes"));
  mesh.cells[0].nodes[3] = -1;
  EXPECT_TRUE(contains(validation_error(mesh), "uses node -1 but the mesh has 4 nodes"));
  EXPECT_THROW(cell_measure(mesh.points, mesh.cells[0]), MeshError);
}

TEST(MeshValidate, RejectsRepeatedNode) {
  const Mesh mesh = single_cell_mesh(unit_tetra_points(), cell_of(CellType::tetra, {0, 1, 1, 3}));
  EXPECT_TRUE(contains(validation_error(mesh), "uses node 1 twice"));
}

TEST(MeshValidate, RejectsEmptyMesh) { EXPECT_EQ(validation_error(Mesh{}), "mesh has no cells"); }

TEST(MeshValidate, RejectsMixedCells) {
  Mesh mesh = single_cell_mesh(unit_tetra_points(), kTetra);
  mesh.cells.push_back(cell_of(CellType::triangle, {0, 1, 2}));
  EXPECT_TRUE(
      contains(validation_error(mesh),
               "mixes volumetric and surface cells: cell 0 is tetra but cell 1 is triangle"));
  EXPECT_THROW((void)mesh.volumetric(), MeshError);
}

TEST(MeshValidate, RejectsNonFiniteCoordinates) {
  Mesh mesh = single_cell_mesh(unit_tetra_points(), kTetra);
  mesh.points[2].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(contains(validation_error(mesh), "node 2 has a non-finite coordinate"));
}

TEST(MeshVolumetric, TellsVolumeFromSurfaceMeshes) {
  EXPECT_TRUE(single_cell_mesh(unit_cube_points(), kHexa).volumetric());
  EXPECT_FALSE(
      single_cell_mesh(unit_tetra_points(), cell_of(CellType::triangle, {0, 1, 2})).volumetric());
  EXPECT_FALSE(Mesh{}.volumetric());
}

}  // namespace
}  // namespace phymul
