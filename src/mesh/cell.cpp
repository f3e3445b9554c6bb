// Cell types, cell measures and mesh validation.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "mesh/cell_tables.hpp"
#include "phymul/mesh.hpp"

namespace phymul {
namespace mesh_detail {
namespace {

constexpr std::array<LocalEdge, 3> kTriangleEdges{{{0, 1}, {1, 2}, {2, 0}}};
constexpr std::array<LocalEdge, 4> kQuadEdges{{{0, 1}, {1, 2}, {2, 3}, {3, 0}}};
constexpr std::array<LocalEdge, 6> kTetraEdges{{{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}}};
constexpr std::array<LocalEdge, 12> kHexaEdges{{{0, 1},
                                                {1, 2},
                                                {2, 3},
                                                {3, 0},
                                                {4, 5},
                                                {5, 6},
                                                {6, 7},
                                                {7, 4},
                                                {0, 4},
                                                {1, 5},
                                                {2, 6},
                                                {3, 7}}};
constexpr std::array<LocalEdge, 9> kWedgeEdges{
    {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}, {2, 5}}};

// Outward faces of positive cells (see the orientation conventions in mesh.hpp).
constexpr std::array<LocalFace, 4> kTetraFaces{
    {{{0, 2, 1, -1}, 3}, {{0, 1, 3, -1}, 3}, {{1, 2, 3, -1}, 3}, {{0, 3, 2, -1}, 3}}};
constexpr std::array<LocalFace, 6> kHexaFaces{{{{0, 3, 2, 1}, 4},
                                               {{4, 5, 6, 7}, 4},
                                               {{0, 1, 5, 4}, 4},
                                               {{1, 2, 6, 5}, 4},
                                               {{2, 3, 7, 6}, 4},
                                               {{3, 0, 4, 7}, 4}}};
// VTK wedge: triangle 0-1-2 faces away from 3-4-5, so it is already outward.
constexpr std::array<LocalFace, 5> kWedgeFaces{{{{0, 1, 2, -1}, 3},
                                                {{3, 5, 4, -1}, 3},
                                                {{0, 3, 4, 1}, 4},
                                                {{1, 4, 5, 2}, 4},
                                                {{2, 5, 3, 0}, 4}}};

// Each corner with its three edge neighbours, ordered so the corner Jacobian is positive.
constexpr std::array<LocalCorner, 8> kHexaCorners{{{0, 1, 3, 4},
                                                   {1, 2, 0, 5},
                                                   {2, 3, 1, 6},
                                                   {3, 0, 2, 7},
                                                   {4, 7, 5, 0},
                                                   {5, 4, 6, 1},
                                                   {6, 5, 7, 2},
                                                   {7, 6, 4, 3}}};
constexpr std::array<LocalCorner, 6> kWedgeCorners{
    {{0, 2, 1, 3}, {1, 0, 2, 4}, {2, 1, 0, 5}, {3, 4, 5, 0}, {4, 5, 3, 1}, {5, 3, 4, 2}}};

[[noreturn]] void throw_unknown_type(CellType type) {
  throw std::invalid_argument("unknown CellType value " + std::to_string(int(type)));
}

}  // namespace

std::span<const LocalEdge> cell_edges(CellType type) {
  switch (type) {
    case CellType::triangle:
      return kTriangleEdges;
    case CellType::quad:
      return kQuadEdges;
    case CellType::tetra:
      return kTetraEdges;
    case CellType::hexa:
      return kHexaEdges;
    case CellType::wedge:
      return kWedgeEdges;
  }
  throw_unknown_type(type);
}

std::span<const LocalFace> cell_faces(CellType type) {
  switch (type) {
    case CellType::triangle:
    case CellType::quad:
      return {};
    case CellType::tetra:
      return kTetraFaces;
    case CellType::hexa:
      return kHexaFaces;
    case CellType::wedge:
      return kWedgeFaces;
  }
  throw_unknown_type(type);
}

std::span<const LocalCorner> cell_corners(CellType type) {
  switch (type) {
    case CellType::triangle:
    case CellType::quad:
    case CellType::tetra:
      return {};
    case CellType::hexa:
      return kHexaCorners;
    case CellType::wedge:
      return kWedgeCorners;
  }
  throw_unknown_type(type);
}

std::array<Triangle, 2> split_quad(const std::array<int, 4>& quad) {
  const int m = int(std::min_element(quad.begin(), quad.end()) - quad.begin());
  const int a = quad[m], b = quad[(m + 1) % 4], c = quad[(m + 2) % 4], d = quad[(m + 3) % 4];
  return {Triangle{a, b, c}, Triangle{a, c, d}};
}

std::array<int, 4> face_nodes(const Cell& cell, const LocalFace& face) {
  std::array<int, 4> ids{-1, -1, -1, -1};
  for (int k = 0; k < face.size; ++k) ids[k] = cell.nodes[face.nodes[k]];
  return ids;
}

std::string format_number(double value) {
  std::ostringstream out;
  out.precision(3);
  out << value;
  return out.str();
}

std::string describe_cell(const Cell& cell, std::ptrdiff_t index) {
  std::ostringstream out;
  out << "cell ";
  if (index >= 0) out << index << ' ';
  out << '(' << cell_type_name(cell.type) << ", nodes";
  for (int node : cell.node_span()) out << ' ' << node;
  out << ')';
  return out.str();
}

void check_node_range(const Cell& cell, std::ptrdiff_t index, std::size_t point_count) {
  for (int node : cell.node_span()) {
    if (node < 0 || std::size_t(node) >= point_count) {
      throw MeshError(describe_cell(cell, index) + " uses node " + std::to_string(node) +
                      " but the mesh has " + std::to_string(point_count) + " nodes");
    }
  }
}

double triple_product(const Vec3& origin, const Vec3& a, const Vec3& b, const Vec3& c) {
  return (a - origin).dot((b - origin).cross(c - origin));
}

}  // namespace mesh_detail

using namespace mesh_detail;

int node_count(CellType type) {
  switch (type) {
    case CellType::triangle:
      return 3;
    case CellType::quad:
      return 4;
    case CellType::tetra:
      return 4;
    case CellType::hexa:
      return 8;
    case CellType::wedge:
      return 6;
  }
  throw_unknown_type(type);
}

bool is_volumetric(CellType type) {
  switch (type) {
    case CellType::triangle:
    case CellType::quad:
      return false;
    case CellType::tetra:
    case CellType::hexa:
    case CellType::wedge:
      return true;
  }
  throw_unknown_type(type);
}

int vtk_cell_type(CellType type) {
  switch (type) {
    case CellType::triangle:
      return 5;
    case CellType::quad:
      return 9;
    case CellType::tetra:
      return 10;
    case CellType::hexa:
      return 12;
    case CellType::wedge:
      return 13;
  }
  throw_unknown_type(type);
}

const char* cell_type_name(CellType type) {
  switch (type) {
    case CellType::triangle:
      return "triangle";
    case CellType::quad:
      return "quad";
    case CellType::tetra:
      return "tetra";
    case CellType::hexa:
      return "hexa";
    case CellType::wedge:
      return "wedge";
  }
  throw_unknown_type(type);
}

// A mesh without cells has no volumetric cell, hence false.
bool Mesh::volumetric() const {
  if (cells.empty()) return false;
  const bool first = is_volumetric(cells.front().type);
  for (std::size_t i = 1; i < cells.size(); ++i) {
    if (is_volumetric(cells[i].type) != first) {
      throw MeshError("mesh mixes volumetric and surface cells: cell 0 is " +
                      std::string(cell_type_name(cells.front().type)) + " but cell " +
                      std::to_string(i) + " is " + cell_type_name(cells[i].type));
    }
  }
  return first;
}

namespace {

double tetra_volume(const std::vector<Vec3>& p, const Cell& cell) {
  const auto& n = cell.nodes;
  return triple_product(p[n[0]], p[n[1]], p[n[2]], p[n[3]]) / 6.0;
}

// Divergence theorem over the outward faces, quads split by split_quad. This is exact for
// planar faces and, for warped ones, the value consistent with boundary_triangles (see
// split_quad). Measured from the cell's first node to keep round-off relative to its size.
double polyhedron_volume(const std::vector<Vec3>& p, const Cell& cell) {
  const Vec3& origin = p[cell.nodes[0]];
  double sum = 0.0;
  for (const LocalFace& face : cell_faces(cell.type)) {
    const std::array<int, 4> ids = face_nodes(cell, face);
    if (face.size == 3) {
      sum += triple_product(origin, p[ids[0]], p[ids[1]], p[ids[2]]);
      continue;
    }
    for (const Triangle& t : split_quad(ids))
      sum += triple_product(origin, p[t[0]], p[t[1]], p[t[2]]);
  }
  return sum / 6.0;
}

double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

double surface_area(const std::vector<Vec3>& p, const Cell& cell) {
  const auto& n = cell.nodes;
  if (cell.type == CellType::triangle) return triangle_area(p[n[0]], p[n[1]], p[n[2]]);
  double area = 0.0;
  for (const Triangle& t : split_quad({n[0], n[1], n[2], n[3]})) {
    area += triangle_area(p[t[0]], p[t[1]], p[t[2]]);
  }
  return area;
}

double mean_edge_length(const std::vector<Vec3>& p, const Cell& cell) {
  const auto edges = cell_edges(cell.type);
  double sum = 0.0;
  for (const LocalEdge& e : edges) sum += (p[cell.nodes[e[1]]] - p[cell.nodes[e[0]]]).norm();
  return sum / double(edges.size());
}

void check_points_finite(const std::vector<Vec3>& points) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      const Vec3& p = points[i];
      throw MeshError("node " + std::to_string(i) + " has a non-finite coordinate (" +
                      format_number(p.x()) + ", " + format_number(p.y()) + ", " +
                      format_number(p.z()) + ")");
    }
  }
}

void check_distinct_nodes(const Cell& cell, std::size_t index) {
  const auto nodes = cell.node_span();
  for (std::size_t a = 0; a < nodes.size(); ++a) {
    for (std::size_t b = a + 1; b < nodes.size(); ++b) {
      if (nodes[a] == nodes[b]) {
        throw MeshError(describe_cell(cell, std::ptrdiff_t(index)) + " uses node " +
                        std::to_string(nodes[a]) + " twice");
      }
    }
  }
}

const char* orientation_hint(CellType type) {
  switch (type) {
    case CellType::tetra:
      return "VTK order needs (p1-p0)x(p2-p0) pointing towards p3";
    case CellType::hexa:
      return "VTK order needs face 0-1-2-3's normal pointing towards 4-5-6-7";
    case CellType::wedge:
      return "VTK order needs triangle 0-1-2's normal pointing away from 3-4-5";
    default:
      return "";
  }
}

// A positive total volume can still hide a fold: every corner tetrahedron must be positive.
void check_corners(const std::vector<Vec3>& p, const Cell& cell, std::size_t index,
                   double tolerance) {
  const auto& n = cell.nodes;
  for (const LocalCorner& c : cell_corners(cell.type)) {
    const double volume = triple_product(p[n[c[0]]], p[n[c[1]]], p[n[c[2]]], p[n[c[3]]]) / 6.0;
    if (volume > tolerance) continue;
    const std::string where = describe_cell(cell, std::ptrdiff_t(index)) + " is " +
                              (volume < 0.0 ? "inverted" : "degenerate") + " at corner " +
                              std::to_string(c[0]) + " (node " + std::to_string(n[c[0]]) +
                              "): corner tetrahedron volume " + format_number(volume) + " m^3";
    throw MeshError(volume < 0.0 ? where + " (the cell is folded or twisted)"
                                 : where + " is below 1e-12 of its mean edge length cubed");
  }
}

void check_shape(const std::vector<Vec3>& p, const Cell& cell, std::size_t index) {
  const bool volumetric = is_volumetric(cell.type);
  const double edge = mean_edge_length(p, cell);
  const double tolerance = 1e-12 * (volumetric ? edge * edge * edge : edge * edge);
  const double measure = cell_measure(p, cell);
  if (!(std::abs(measure) > tolerance)) {
    throw MeshError(describe_cell(cell, std::ptrdiff_t(index)) + " is degenerate: " +
                    (volumetric ? "volume " : "area ") + format_number(measure) +
                    (volumetric ? " m^3" : " m^2") + " is below 1e-12 of its mean edge length " +
                    (volumetric ? "cubed" : "squared") + " (" + format_number(edge) + " m)");
  }
  if (measure < 0.0) {
    throw MeshError(describe_cell(cell, std::ptrdiff_t(index)) + " is inverted: signed volume " +
                    format_number(measure) + " m^3 (" + orientation_hint(cell.type) + ")");
  }
  check_corners(p, cell, index, tolerance);
}

}  // namespace

double cell_measure(const std::vector<Vec3>& points, const Cell& cell) {
  check_node_range(cell, -1, points.size());
  switch (cell.type) {
    case CellType::tetra:
      return tetra_volume(points, cell);
    case CellType::hexa:
    case CellType::wedge:
      return polyhedron_volume(points, cell);
    case CellType::triangle:
    case CellType::quad:
      return surface_area(points, cell);
  }
  throw_unknown_type(cell.type);
}

std::array<Vec3, 2> bounding_box(std::span<const Vec3> points) {
  if (points.empty()) return {Vec3::Zero(), Vec3::Zero()};
  Vec3 lo = points.front(), hi = lo;
  for (const Vec3& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  return {lo, hi};
}

void validate(const Mesh& mesh) {
  if (mesh.cells.empty()) throw MeshError("mesh has no cells");
  check_points_finite(mesh.points);
  for (std::size_t i = 0; i < mesh.cells.size(); ++i) {
    check_node_range(mesh.cells[i], std::ptrdiff_t(i), mesh.points.size());
    check_distinct_nodes(mesh.cells[i], i);
  }
  (void)mesh.volumetric();  // throws MeshError when volumetric and surface cells are mixed
  for (std::size_t i = 0; i < mesh.cells.size(); ++i) check_shape(mesh.points, mesh.cells[i], i);
}

}  // namespace phymul
