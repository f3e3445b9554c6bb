// Meshes: cells, topology and generators. Node numbering and cell node order follow VTK.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace phymul {

using Vec3 = Eigen::Vector3d;
using Triangle = std::array<int, 3>;

// Linear cells, VTK node order (VTK_TRIANGLE 5, VTK_QUAD 9, VTK_TETRA 10, VTK_HEXAHEDRON 12,
// VTK_WEDGE 13). A positive tetra has (p1-p0)x(p2-p0) pointing towards p3; a positive hexa
// has its face 0-1-2-3 normal pointing towards 4-5-6-7; a positive VTK wedge has its
// triangle 0-1-2 normal pointing AWAY from 3-4-5 (VTK's convention).
enum class CellType : std::uint8_t { triangle, quad, tetra, hexa, wedge };

int node_count(CellType type);
bool is_volumetric(CellType type);
int vtk_cell_type(CellType type);
const char* cell_type_name(CellType type);

struct Cell {
  CellType type = CellType::tetra;
  std::array<int, 8> nodes{-1, -1, -1, -1, -1, -1, -1, -1};  // first node_count(type) used
  std::span<const int> node_span() const { return {nodes.data(), size_t(node_count(type))}; }
};

struct Mesh {
  std::vector<Vec3> points;  // m
  std::vector<Cell> cells;
  // Named node groups, e.g. the faces of a generated box: "left" (x-), "right" (x+),
  // "front" (y-), "back" (y+), "bottom" (z-), "top" (z+). Sorted, unique.
  std::map<std::string, std::vector<int>> node_sets;

  bool volumetric() const;  // true when every cell is volumetric; mixing is a MeshError
};

// Raised for bad meshes; the message names the cell (index, type, nodes) and the problem.
class MeshError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Signed volume (m^3) of a volumetric cell, area (m^2, positive) of a surface cell.
double cell_measure(const std::vector<Vec3>& points, const Cell& cell);

// Lower and upper corners (m) of the axis-aligned box around the points; zero for none.
std::array<Vec3, 2> bounding_box(std::span<const Vec3> points);

// The three tetrahedra of a wedge, cut so that neighbouring wedges split their shared
// quadrilateral the same way (each quad along the diagonal through its smallest node id).
// Their orientation is not fixed: order them by their signed volume where it matters.
std::array<Cell, 3> wedge_tetrahedra(const Cell& wedge);

// Throws MeshError for: empty mesh, node index out of range, repeated node in a cell,
// volumetric and surface cells mixed, inverted cells (negative volume, for hexa and wedge
// also any negative corner tetra / Jacobian at a corner), degenerate cells (|measure| below
// 1e-12 of the cube/square of the mean edge length), non-finite coordinates.
void validate(const Mesh& mesh);

// Compressed rows: the items of row i are indices[offsets[i] .. offsets[i+1]).
struct Adjacency {
  std::vector<int> offsets{0};
  std::vector<int> indices;
  int rows() const { return int(offsets.size()) - 1; }
  std::span<const int> row(int i) const {
    return {indices.data() + offsets[i], size_t(offsets[i + 1] - offsets[i])};
  }
};

// For every node of the mesh: the nodes sharing a cell edge with it, sorted ascending.
// Nodes used by no cell get an empty row. Rows == mesh.points.size().
Adjacency edge_neighbours(const Mesh& mesh);

// Surface meshes (triangles and quads) only: for every node, its edge neighbours ordered
// around it, counter-clockwise seen from the side the cell normals point to. For a node on
// the border of an open surface the fan is ordered the same way, starting at a border
// neighbour. Throws MeshError for a non-manifold or inconsistently oriented surface.
Adjacency ordered_one_rings(const Mesh& mesh);

// The boundary surface as triangles. Every quad (cell face or surface cell) is split along
// the diagonal through its smallest node id, so a warped face shared by two cells splits the
// same way from both sides and cell volumes add up exactly to the enclosed volume:
// volumetric mesh: the faces used by exactly one cell, oriented outward;
// surface mesh: the cells themselves with their own orientation.
std::vector<Triangle> boundary_triangles(const Mesh& mesh);

// True when every edge of the triangles is used exactly twice, once in each direction.
bool is_closed(std::span<const Triangle> triangles);

// Divergence-theorem volume (m^3) enclosed by outward triangles: (1/6) sum a.(b x c).
double enclosed_volume(std::span<const Vec3> points, std::span<const Triangle> triangles);

// Per node: its share of the cells' measures, each cell split equally among its nodes
// (m^3 for volumetric meshes, m^2 for surface meshes).
std::vector<double> lumped_measure(const Mesh& mesh);

// ---- Generators. All sizes in metres; the result is centred on `center`.

// Box of size (x, y, z) split into cells[0] x cells[1] x cells[2] hexahedra, or each hexa
// split into 6 tetrahedra (conforming). Node sets: the six face names above.
Mesh make_box(const Vec3& size, const std::array<int, 3>& cells, CellType type,
              const Vec3& center = Vec3::Zero());

// Closed triangulated ellipsoid surface (subdivided icosahedron, outward normals) with the
// given semi-axes. subdivisions 0..7 (20 * 4^s triangles). Node sets: "top" and "bottom"
// (the single node of largest / smallest z).
Mesh make_ellipsoid_surface(const Vec3& radii, int subdivisions, const Vec3& center = Vec3::Zero());

// Volume mesh of an ellipsoid: `layers` concentric shells of the subdivided icosahedron,
// joined by wedges, with tetrahedra around the centre node. Its boundary is the surface
// above. Node sets: "surface" (all outer nodes), "top", "bottom".
Mesh make_ellipsoid_volume(const Vec3& radii, int subdivisions, int layers,
                           const Vec3& center = Vec3::Zero());

// Volume mesh of an ellipsoid in hexahedra: a grid of cells^3 (cells even, >= 2) mapped from
// a cube, cells of nearly one size. Node sets: "surface", "top", "bottom" (the poles).
Mesh make_ellipsoid_hexa(const Vec3& radii, int cells, const Vec3& center = Vec3::Zero());

// Cylinder along z of the given radius and length. around >= 3 nodes per ring, along >= 1
// cell layers. Surface: closed (caps triangulated with a centre node). Volume: wedges
// (a triangulated disk with `rings` rings extruded). Node sets: "top", "bottom" (cap
// nodes), "side".
Mesh make_cylinder_surface(double radius, double length, int around, int along,
                           const Vec3& center = Vec3::Zero());
Mesh make_cylinder_volume(double radius, double length, int around, int along, int rings,
                          const Vec3& center = Vec3::Zero());

}  // namespace phymul
