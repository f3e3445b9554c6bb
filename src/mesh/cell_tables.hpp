// Internal to the mesh module: the local edge, face and corner tables of each cell type and
// the helpers that cell.cpp, topology.cpp and generators.cpp share.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <span>
#include <string>

#include "phymul/mesh.hpp"

namespace phymul::mesh_detail {

using LocalEdge = std::array<int, 2>;

// A face as local node indices, counter-clockwise seen from outside a positive cell.
// Triangular faces leave nodes[3] at -1.
struct LocalFace {
  std::array<int, 4> nodes;
  int size;
};

// A corner tetrahedron (corner, a, b, c): for a positive cell,
// (p_a - p_corner) . ((p_b - p_corner) x (p_c - p_corner)) > 0.
using LocalCorner = std::array<int, 4>;

std::span<const LocalEdge> cell_edges(CellType type);
// Empty for surface cells: their only "face" is the cell itself.
std::span<const LocalFace> cell_faces(CellType type);
// Empty for tetra (its single corner tetrahedron is the cell) and surface cells.
std::span<const LocalCorner> cell_corners(CellType type);

// The one quad split used everywhere (cell volumes, cell areas, boundary triangles): the
// diagonal through the quad's smallest global node id, i.e. diagonal 0-2 once the quad is
// rotated to start at that node. Because the choice depends only on the node ids, two cells
// sharing a non-planar quad face split it identically, so its two contributions to the
// divergence-theorem volumes cancel exactly and the cell volumes add up to the volume
// enclosed by the boundary triangles.
std::array<Triangle, 2> split_quad(const std::array<int, 4>& quad);

// The global node ids of a local face of `cell`.
std::array<int, 4> face_nodes(const Cell& cell, const LocalFace& face);

// "cell 12 (hexa, nodes 3 4 9 8 10 11 16 15)"; index < 0 leaves out the number.
std::string describe_cell(const Cell& cell, std::ptrdiff_t index);

// Compact number for messages, e.g. "-1.2e-09".
std::string format_number(double value);

// Throws MeshError naming the cell when one of its node ids is not in [0, point_count).
void check_node_range(const Cell& cell, std::ptrdiff_t index, std::size_t point_count);

// (a-o).((b-o)x(c-o)) with o = origin: six times the signed volume of tetrahedron o-a-b-c.
double triple_product(const Vec3& origin, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace phymul::mesh_detail
