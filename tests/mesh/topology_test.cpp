// Edge adjacency, one-rings, boundary surfaces, enclosed volume and lumped measures.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <numeric>
#include <span>
#include <string>
#include <vector>

#include "mesh_test_util.hpp"
#include "phymul/mesh.hpp"

namespace phymul {
namespace {

using mesh_test::cell_of;
using mesh_test::contains;
using mesh_test::total_measure;

std::vector<int> as_vector(std::span<const int> row) { return {row.begin(), row.end()}; }

// The same cycle, rotated to start at its smallest node.
std::vector<int> canonical_cycle(std::vector<int> ring) {
  std::rotate(ring.begin(), std::min_element(ring.begin(), ring.end()), ring.end());
  return ring;
}

// 3 x 3 nodes (node i + 3 j at (i, j, 0)) in 2 x 2 quads facing +z.
Mesh quad_patch() {
  Mesh mesh;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) mesh.points.emplace_back(i, j, 0.0);
  }
  for (int j = 0; j < 2; ++j) {
    for (int i = 0; i < 2; ++i) {
      const int a = i + 3 * j;
      mesh.cells.push_back(cell_of(CellType::quad, {a, a + 1, a + 4, a + 3}));
    }
  }
  return mesh;
}

Mesh unit_tetra_mesh() {
  Mesh mesh;
  mesh.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.cells = {cell_of(CellType::tetra, {0, 1, 2, 3})};
  return mesh;
}

std::string mesh_error(const std::function<void()>& action) {
  try {
    action();
  } catch (const MeshError& e) {
    return e.what();
  }
  return "";
}

TEST(MeshEdgeNeighbours, SingleHexaNodeHasThree) {
  const Mesh mesh = make_box(Vec3::Ones(), {1, 1, 1}, CellType::hexa);
  const Adjacency adjacency = edge_neighbours(mesh);
  ASSERT_EQ(adjacency.rows(), 8);
  for (int node = 0; node < 8; ++node) EXPECT_EQ(adjacency.row(node).size(), 3u) << node;
  EXPECT_EQ(as_vector(adjacency.row(0)), (std::vector<int>{1, 2, 4}));  // x, y and z neighbour
}

TEST(MeshEdgeNeighbours, InteriorNodeOf2x2x2GridHasSix) {
  const Mesh mesh = make_box(Vec3::Ones(), {2, 2, 2}, CellType::hexa);
  const Adjacency adjacency = edge_neighbours(mesh);
  ASSERT_EQ(adjacency.rows(), 27);
  // Node 13 = (1, 1, 1) is the centre; node id = i + 3 j + 9 k.
  EXPECT_EQ(as_vector(adjacency.row(13)), (std::vector<int>{4, 10, 12, 14, 16, 22}));
  EXPECT_EQ(adjacency.row(0).size(), 3u);
  EXPECT_EQ(adjacency.indices.size(), 2u * 54u);  // 54 grid edges, both directions
}

TEST(MeshEdgeNeighbours, KuhnTetraSplitAddsTheMainDiagonals) {
  const Mesh mesh = make_box(Vec3::Ones(), {1, 1, 1}, CellType::tetra);
  const Adjacency adjacency = edge_neighbours(mesh);
  // Corner (0,0,0) is on all six tetras: it sees every other corner.
  EXPECT_EQ(as_vector(adjacency.row(0)), (std::vector<int>{1, 2, 3, 4, 5, 6, 7}));
  // Corner (1,0,0) = node 1 sees (0,0,0), (1,1,0), (1,0,1) and (1,1,1).
  EXPECT_EQ(as_vector(adjacency.row(1)), (std::vector<int>{0, 3, 5, 7}));
}

TEST(MeshEdgeNeighbours, UnusedNodeHasEmptyRow) {
  Mesh mesh = unit_tetra_mesh();
  mesh.points.emplace_back(5, 5, 5);
  const Adjacency adjacency = edge_neighbours(mesh);
  ASSERT_EQ(adjacency.rows(), 5);
  EXPECT_TRUE(adjacency.row(4).empty());
  EXPECT_EQ(as_vector(adjacency.row(3)), (std::vector<int>{0, 1, 2}));
}

TEST(MeshOrderedOneRings, IcosphereRingsAreOutwardCycles) {
  const Mesh mesh = make_ellipsoid_surface(Vec3(1.0, 2.0, 3.0), 2);
  const Adjacency rings = ordered_one_rings(mesh);
  const Adjacency neighbours = edge_neighbours(mesh);
  ASSERT_EQ(rings.rows(), int(mesh.points.size()));
  int valence_five = 0;
  for (int node = 0; node < rings.rows(); ++node) {
    std::vector<int> ring = as_vector(rings.row(node));
    ASSERT_TRUE(ring.size() == 5 || ring.size() == 6) << node;
    valence_five += ring.size() == 5 ? 1 : 0;
    Vec3 normal = Vec3::Zero();
    const Vec3& p = mesh.points[node];
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const int a = ring[i], b = ring[(i + 1) % ring.size()];
      const auto row_a = neighbours.row(a);
      EXPECT_TRUE(std::binary_search(row_a.begin(), row_a.end(), b)) << "ring not a cycle";
      normal += (mesh.points[a] - p).cross(mesh.points[b] - p);
    }
    EXPECT_GT(normal.dot(p), 0.0) << "ring of node " << node << " is clockwise";
    std::sort(ring.begin(), ring.end());
    EXPECT_EQ(ring, as_vector(neighbours.row(node)));
  }
  EXPECT_EQ(valence_five, 12);  // the icosahedron's corners
}

TEST(MeshOrderedOneRings, OpenQuadPatchStartsAtABorderNeighbour) {
  const Adjacency rings = ordered_one_rings(quad_patch());
  // Centre: east 5, north 7, west 3, south 1, counter-clockwise seen from +z.
  EXPECT_EQ(canonical_cycle(as_vector(rings.row(4))), (std::vector<int>{1, 5, 7, 3}));
  EXPECT_EQ(as_vector(rings.row(0)), (std::vector<int>{1, 3}));     // corner: east then north
  EXPECT_EQ(as_vector(rings.row(1)), (std::vector<int>{2, 4, 0}));  // border: east, north, west
  EXPECT_EQ(as_vector(rings.row(8)), (std::vector<int>{7, 5}));     // corner: west then south
}

TEST(MeshOrderedOneRings, FlippedTriangleThrowsAndOpensTheSurface) {
  Mesh mesh = make_ellipsoid_surface(Vec3::Ones(), 1);
  ASSERT_TRUE(is_closed(boundary_triangles(mesh)));
  std::swap(mesh.cells[5].nodes[1], mesh.cells[5].nodes[2]);
  const std::string message = mesh_error([&] { ordered_one_rings(mesh); });
  EXPECT_TRUE(contains(message, "inconsistently oriented"));
  const int named = std::stoi(message.substr(message.find("node ") + 5));
  const auto flipped = mesh.cells[5].node_span();
  EXPECT_NE(std::find(flipped.begin(), flipped.end(), named), flipped.end()) << message;
  EXPECT_FALSE(is_closed(boundary_triangles(mesh)));
}

TEST(MeshOrderedOneRings, NonManifoldSurfacesThrow) {
  Mesh bowtie;  // two triangles touching only at node 0
  bowtie.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  bowtie.cells = {cell_of(CellType::triangle, {0, 1, 2}), cell_of(CellType::triangle, {0, 3, 4})};
  const std::string bowtie_message = mesh_error([&] { ordered_one_rings(bowtie); });
  EXPECT_TRUE(contains(bowtie_message, "node 0: the surface is non-manifold"));

  Mesh fin;  // three triangles on edge 0-1
  fin.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  fin.cells = {cell_of(CellType::triangle, {0, 1, 2}), cell_of(CellType::triangle, {1, 0, 3}),
               cell_of(CellType::triangle, {0, 1, 4})};
  EXPECT_TRUE(contains(mesh_error([&] { ordered_one_rings(fin); }),
                       "node 0: the surface is non-manifold: edge 0-1 is shared by 3 cells"));
}

TEST(MeshOrderedOneRings, RejectsVolumeMeshes) {
  EXPECT_TRUE(
      contains(mesh_error([] { ordered_one_rings(unit_tetra_mesh()); }), "needs a surface mesh"));
}

TEST(MeshBoundaryTriangles, SingleHexaGivesTwelveOutwardTriangles) {
  const Mesh mesh = make_box(Vec3::Ones(), {1, 1, 1}, CellType::hexa);
  const std::vector<Triangle> boundary = boundary_triangles(mesh);
  ASSERT_EQ(boundary.size(), 12u);
  EXPECT_TRUE(is_closed(boundary));
  EXPECT_NEAR(enclosed_volume(mesh.points, boundary), 1.0, 1e-15);
  for (const auto& [a, b, c] : boundary) {
    const Vec3& p = mesh.points[a];
    const Vec3 normal = (mesh.points[b] - p).cross(mesh.points[c] - p);
    EXPECT_GT(normal.dot((p + mesh.points[b] + mesh.points[c]) / 3.0), 0.0);
  }
}

TEST(MeshBoundaryTriangles, InteriorFacesCancel) {
  const Mesh mesh = make_box(Vec3::Constant(2.0), {2, 2, 2}, CellType::hexa);
  const std::vector<Triangle> boundary = boundary_triangles(mesh);
  EXPECT_EQ(boundary.size(), 6u * 4u * 2u);
  EXPECT_TRUE(is_closed(boundary));
  EXPECT_NEAR(enclosed_volume(mesh.points, boundary), 8.0, 1e-14);
}

TEST(MeshBoundaryTriangles, SurfaceMeshGivesItsOwnCells) {
  const Mesh mesh = quad_patch();
  const std::vector<Triangle> triangles = boundary_triangles(mesh);
  ASSERT_EQ(triangles.size(), 8u);
  EXPECT_FALSE(is_closed(triangles));  // an open patch
  for (const auto& [a, b, c] : triangles) {
    const Vec3 normal = (mesh.points[b] - mesh.points[a]).cross(mesh.points[c] - mesh.points[a]);
    EXPECT_NEAR(normal.z(), 1.0, 1e-15);  // half a unit quad, facing +z like the quads
  }
}

TEST(MeshBoundaryTriangles, FaceOfThreeCellsThrows) {
  Mesh mesh = unit_tetra_mesh();
  mesh.points.emplace_back(0, 0, -1);
  mesh.points.emplace_back(0.1, 0.1, 2);
  mesh.cells.push_back(cell_of(CellType::tetra, {0, 2, 1, 4}));
  mesh.cells.push_back(cell_of(CellType::tetra, {0, 1, 2, 5}));
  EXPECT_TRUE(contains(mesh_error([&] { boundary_triangles(mesh); }),
                       "face (nodes 0 1 2) is shared by 3 cells (0, 1, 2)"));
}

TEST(MeshIsClosed, NeedsEveryEdgeOnceInEachDirection) {
  const Mesh mesh = unit_tetra_mesh();
  std::vector<Triangle> surface = boundary_triangles(mesh);
  ASSERT_EQ(surface.size(), 4u);
  EXPECT_TRUE(is_closed(surface));
  EXPECT_FALSE(is_closed(std::span(surface).first(3)));  // a hole
  std::vector<Triangle> doubled = surface;
  doubled.insert(doubled.end(), surface.begin(), surface.end());
  EXPECT_FALSE(is_closed(doubled));  // every edge four times
  std::swap(surface[0][1], surface[0][2]);
  EXPECT_FALSE(is_closed(surface));  // one triangle flipped
  EXPECT_FALSE(is_closed({}));
}

TEST(MeshEnclosedVolume, UnitTetraSurface) {
  Mesh mesh = unit_tetra_mesh();
  for (Vec3& p : mesh.points) p += Vec3(10.0, -20.0, 30.0);
  std::vector<Triangle> surface = boundary_triangles(mesh);
  EXPECT_NEAR(enclosed_volume(mesh.points, surface), 1.0 / 6.0, 1e-12);
  for (Triangle& t : surface) std::swap(t[1], t[2]);
  EXPECT_NEAR(enclosed_volume(mesh.points, surface), -1.0 / 6.0, 1e-12);  // inward
}

TEST(MeshLumpedMeasure, SplitsEachCellEquallyAmongItsNodes) {
  const Mesh hexas = make_box(Vec3::Constant(2.0), {2, 2, 2}, CellType::hexa);
  const std::vector<double> lumped = lumped_measure(hexas);
  EXPECT_NEAR(lumped[0], 1.0 / 8.0, 1e-15);  // a corner: 1/8 of one unit hexa
  EXPECT_NEAR(lumped[13], 1.0, 1e-15);       // the centre: 1/8 of all eight
  EXPECT_NEAR(std::accumulate(lumped.begin(), lumped.end(), 0.0), 8.0, 1e-14);
}

TEST(MeshLumpedMeasure, SumsToTheTotalMeasure) {
  const Mesh tetras = make_box(Vec3(1.0, 2.0, 3.0), {3, 4, 5}, CellType::tetra);
  const std::vector<double> volume = lumped_measure(tetras);
  EXPECT_NEAR(std::accumulate(volume.begin(), volume.end(), 0.0), 6.0, 6.0 * 1e-13);
  const Mesh cylinder = make_cylinder_surface(0.5, 2.0, 12, 3);
  const std::vector<double> area = lumped_measure(cylinder);
  EXPECT_NEAR(std::accumulate(area.begin(), area.end(), 0.0), total_measure(cylinder), 1e-13);
}

// 40^3 hexas (68921 nodes): building the mesh and its topology must stay far below a second;
// the bound here only catches a quadratic algorithm on a loaded machine.
TEST(MeshTopology, LargeBoxCounts) {
  // Speed is measured by the benchmarks; here the 40^3 grid's topology is counted exactly.
  const Mesh mesh = make_box(Vec3::Ones(), {40, 40, 40}, CellType::hexa);
  validate(mesh);
  const Adjacency adjacency = edge_neighbours(mesh);
  const std::vector<Triangle> boundary = boundary_triangles(mesh);
  EXPECT_EQ(mesh.points.size(), 68921u);
  EXPECT_EQ(adjacency.indices.size(), 2u * 3u * 40u * 41u * 41u);
  EXPECT_EQ(boundary.size(), 6u * 40u * 40u * 2u);
  EXPECT_TRUE(is_closed(boundary));
}

}  // namespace
}  // namespace phymul
