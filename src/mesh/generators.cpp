// Mesh generators: box, ellipsoid and cylinder, as surfaces or volumes. Every generated
// volumetric cell is positive in the VTK sense and every surface triangle faces outward,
// so validate() accepts the meshes and boundary_triangles() encloses a positive volume.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "mesh/cell_tables.hpp"
#include "phymul/mesh.hpp"

namespace phymul {

using mesh_detail::format_number;

namespace {

// Far below what fits in an int for every cell count derived from it (at most 6 per node).
constexpr double kMaxNodes = 5e7;

// ---- Argument checks: each names the generator, the argument, the range and the value.

[[noreturn]] void reject(const char* generator, const std::string& what) {
  throw std::invalid_argument(std::string(generator) + ": " + what);
}

void check_length(const char* generator, const std::string& name, double value) {
  if (!(std::isfinite(value) && value > 0.0)) {
    reject(generator, name + " must be a finite length > 0 m (got " + format_number(value) + ")");
  }
}

void check_at_least(const char* generator, const std::string& name, int value, int minimum) {
  if (value < minimum) {
    reject(generator, name + " must be >= " + std::to_string(minimum) + " (got " +
                          std::to_string(value) + ")");
  }
}

void check_center(const char* generator, const Vec3& center) {
  if (!center.allFinite()) {
    reject(generator, "center must be finite (got (" + format_number(center.x()) + ", " +
                          format_number(center.y()) + ", " + format_number(center.z()) + "))");
  }
}

void check_node_budget(const char* generator, const std::string& arguments, double nodes) {
  if (nodes > kMaxNodes) {
    reject(generator, arguments + " would give " + format_number(nodes) + " nodes; at most " +
                          format_number(kMaxNodes) + " are supported");
  }
}

void check_subdivisions(const char* generator, int subdivisions) {
  if (subdivisions < 0 || subdivisions > 7) {
    reject(generator, "subdivisions must be in 0..7 (got " + std::to_string(subdivisions) + ")");
  }
}

void check_radii(const char* generator, const Vec3& radii) {
  for (int i = 0; i < 3; ++i) check_length(generator, "radii[" + std::to_string(i) + "]", radii[i]);
}

Cell make_cell(CellType type, std::initializer_list<int> nodes) {
  Cell cell;
  cell.type = type;
  std::copy(nodes.begin(), nodes.end(), cell.nodes.begin());
  return cell;
}

std::vector<int> index_range(int first, int count) {
  std::vector<int> ids(count);
  for (int i = 0; i < count; ++i) ids[i] = first + i;
  return ids;
}

// ---- Box.

struct BoxGrid {
  int nx, ny, nz;
  int id(int i, int j, int k) const { return i + (nx + 1) * (j + (ny + 1) * k); }
  int node_count() const { return (nx + 1) * (ny + 1) * (nz + 1); }
};

// The Kuhn (Freudenthal) split of a hexa into 6 tetrahedra around its diagonal 0-6, one per
// monotone path 0 -> 6 along the edges. Every hexa of the grid uses the same diagonal
// direction, so neighbouring hexas split their shared face identically (conforming).
// Odd axis permutations have their last two nodes swapped to keep each tetra positive.
constexpr std::array<std::array<int, 4>, 6> kKuhnTetras{
    {{0, 1, 2, 6}, {0, 1, 6, 5}, {0, 3, 6, 2}, {0, 3, 7, 6}, {0, 4, 5, 6}, {0, 4, 6, 7}}};

std::array<int, 8> hexa_corners(const BoxGrid& g, int i, int j, int k) {
  return {
      g.id(i, j, k),     g.id(i + 1, j, k),     g.id(i + 1, j + 1, k),     g.id(i, j + 1, k),
      g.id(i, j, k + 1), g.id(i + 1, j, k + 1), g.id(i + 1, j + 1, k + 1), g.id(i, j + 1, k + 1)};
}

void add_box_cells(const BoxGrid& g, CellType type, std::vector<Cell>& cells) {
  cells.reserve(std::size_t(g.nx) * g.ny * g.nz * (type == CellType::hexa ? 1 : 6));
  for (int k = 0; k < g.nz; ++k) {
    for (int j = 0; j < g.ny; ++j) {
      for (int i = 0; i < g.nx; ++i) {
        const std::array<int, 8> c = hexa_corners(g, i, j, k);
        if (type == CellType::hexa) {
          cells.push_back(make_cell(type, {c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]}));
          continue;
        }
        for (const auto& t : kKuhnTetras) {
          cells.push_back(make_cell(type, {c[t[0]], c[t[1]], c[t[2]], c[t[3]]}));
        }
      }
    }
  }
}

void add_box_node_sets(const BoxGrid& g, Mesh& mesh) {
  auto& sets = mesh.node_sets;
  for (int k = 0; k <= g.nz; ++k) {
    for (int j = 0; j <= g.ny; ++j) {
      for (int i = 0; i <= g.nx; ++i) {
        const int id = g.id(i, j, k);
        if (i == 0) sets["left"].push_back(id);
        if (i == g.nx) sets["right"].push_back(id);
        if (j == 0) sets["front"].push_back(id);
        if (j == g.ny) sets["back"].push_back(id);
        if (k == 0) sets["bottom"].push_back(id);
        if (k == g.nz) sets["top"].push_back(id);
      }
    }
  }
}

// ---- Icosphere.

struct Icosphere {
  std::vector<Vec3> unit;  // on the unit sphere
  std::vector<Triangle> triangles;
};

// Poles on the z axis, so that "top" and "bottom" are single nodes at every subdivision.
constexpr int kNorthPole = 0, kSouthPole = 11;

Icosphere base_icosahedron() {
  Icosphere ico;
  const double h = 1.0 / std::sqrt(5.0), r = 2.0 / std::sqrt(5.0);
  ico.unit.push_back(Vec3::UnitZ());
  for (int ring = 0; ring < 2; ++ring) {
    for (int k = 0; k < 5; ++k) {
      const double angle = 2.0 * std::numbers::pi * (k + 0.5 * ring) / 5.0;
      ico.unit.emplace_back(r * std::cos(angle), r * std::sin(angle), ring == 0 ? h : -h);
    }
  }
  ico.unit.push_back(-Vec3::UnitZ());
  for (int k = 0; k < 5; ++k) {
    const int kn = (k + 1) % 5;
    const int upper = 1 + k, upper_next = 1 + kn, lower = 6 + k, lower_next = 6 + kn;
    ico.triangles.push_back({kNorthPole, upper, upper_next});
    ico.triangles.push_back({upper, lower, upper_next});
    ico.triangles.push_back({upper_next, lower, lower_next});
    ico.triangles.push_back({kSouthPole, lower_next, lower});
  }
  return ico;
}

std::uint64_t edge_key(int a, int b) {
  return std::uint64_t(std::min(a, b)) << 32 | std::uint64_t(std::max(a, b));
}

// Splits every triangle into four at its edge midpoints, pushed back onto the sphere; the
// corner triangles keep their orientation.
void subdivide(Icosphere& ico) {
  std::vector<std::uint64_t> edges;
  edges.reserve(ico.triangles.size() * 3);
  for (const Triangle& t : ico.triangles) {
    for (int k = 0; k < 3; ++k) edges.push_back(edge_key(t[k], t[(k + 1) % 3]));
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  const int first_midpoint = int(ico.unit.size());
  for (std::uint64_t e : edges) {
    ico.unit.push_back((ico.unit[e >> 32] + ico.unit[e & 0xffffffffu]).normalized());
  }
  const auto midpoint = [&](int a, int b) {
    const auto it = std::lower_bound(edges.begin(), edges.end(), edge_key(a, b));
    return first_midpoint + int(it - edges.begin());
  };
  std::vector<Triangle> refined;
  refined.reserve(ico.triangles.size() * 4);
  for (const auto& [a, b, c] : ico.triangles) {
    const int ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    refined.push_back({a, ab, ca});
    refined.push_back({ab, b, bc});
    refined.push_back({ca, bc, c});
    refined.push_back({ab, bc, ca});
  }
  ico.triangles = std::move(refined);
}

Icosphere make_icosphere(int subdivisions) {
  Icosphere ico = base_icosahedron();
  for (int s = 0; s < subdivisions; ++s) subdivide(ico);
  return ico;
}

double icosphere_node_count(int subdivisions) { return 10.0 * std::pow(4.0, subdivisions) + 2; }

// ---- Cylinder.

// Ring k of `rings` carries about around * k / rings nodes, so the disk triangles keep a
// similar size and shape from the centre to the rim; the rim carries exactly `around`.
// Fewer nodes than the next ring out are only used where the inner ring fits inside that
// ring's polygon with a quarter ring spacing to spare (few-sided polygons are far from
// their circle); otherwise the ring copies the next one's count, a scaled copy of it,
// which always nests and keeps every stitched triangle positive.
std::vector<int> ring_sizes(int around, int rings) {
  std::vector<int> sizes(rings);
  sizes[rings - 1] = around;
  for (int k = rings - 1; k >= 1; --k) {
    const int outer = sizes[k];
    const int wanted = std::max(3, int(std::lround(double(around) * k / rings)));
    const bool nests = k + 0.25 <= (k + 1) * std::cos(std::numbers::pi / outer);
    sizes[k - 1] = wanted < outer && nests ? wanted : outer;
  }
  return sizes;
}

// A triangulated disk in the xy plane: a centre node, then the rings from the inside out.
// Triangles are counter-clockwise seen from +z.
struct Disk {
  std::vector<Eigen::Vector2d> points;
  std::vector<Triangle> triangles;
  int rim_begin = 0, rim_count = 0;
};

void add_ring(double radius, int count, Disk& disk) {
  for (int m = 0; m < count; ++m) {
    const double angle = 2.0 * std::numbers::pi * m / count;
    disk.points.emplace_back(radius * std::cos(angle), radius * std::sin(angle));
  }
}

// Triangulates the strip between two rings that both start at angle 0, advancing on one
// ring at a time along the shorter of the two candidate diagonals (the Delaunay-like choice
// for such strips). Because the inner ring nests inside the outer polygon (ring_sizes),
// triangles on an outer edge are always positive; the distance rule keeps those on an
// inner edge local, hence positive too (checked over many parameters by the tests).
void stitch_rings(int inner_begin, int inner, int outer_begin, int outer, Disk& disk) {
  const auto in = [&](int i) { return inner_begin + i % inner; };
  const auto out = [&](int o) { return outer_begin + o % outer; };
  const auto distance = [&](int a, int b) {
    return (disk.points[a] - disk.points[b]).squaredNorm();
  };
  for (int i = 0, o = 0; i < inner || o < outer;) {
    const bool advance_outer =
        i == inner || (o < outer && distance(in(i), out(o + 1)) <= distance(in(i + 1), out(o)));
    if (advance_outer) {
      disk.triangles.push_back({in(i), out(o), out(o + 1)});
      ++o;
    } else {
      disk.triangles.push_back({in(i), out(o), in(i + 1)});
      ++i;
    }
  }
}

Disk make_disk(double radius, int around, int rings) {
  Disk disk;
  disk.points.emplace_back(0.0, 0.0);
  const std::vector<int> sizes = ring_sizes(around, rings);
  int begin = 1;
  for (int k = 1; k <= rings; ++k) {
    const int count = sizes[k - 1];
    add_ring(radius * k / rings, count, disk);
    if (k == 1) {
      for (int m = 0; m < count; ++m) disk.triangles.push_back({0, 1 + m, 1 + (m + 1) % count});
    } else {
      const int inner = sizes[k - 2];
      stitch_rings(begin - inner, inner, begin, count, disk);
    }
    disk.rim_begin = begin;
    disk.rim_count = count;
    begin += count;
  }
  return disk;
}

void check_cylinder(const char* generator, double radius, double length, int around, int along,
                    const Vec3& center) {
  check_length(generator, "radius", radius);
  check_length(generator, "length", length);
  check_at_least(generator, "around", around, 3);
  check_at_least(generator, "along", along, 1);
  check_center(generator, center);
}

std::string arguments_text(const std::string& name, std::initializer_list<int> values) {
  std::string text = name + " (";
  for (auto it = values.begin(); it != values.end(); ++it) {
    text += (it == values.begin() ? "" : ", ") + std::to_string(*it);
  }
  return text + ")";
}

}  // namespace

Mesh make_box(const Vec3& size, const std::array<int, 3>& cells, CellType type,
              const Vec3& center) {
  const char* generator = "make_box";
  for (int i = 0; i < 3; ++i) {
    check_length(generator, "size[" + std::to_string(i) + "]", size[i]);
    check_at_least(generator, "cells[" + std::to_string(i) + "]", cells[i], 1);
  }
  if (type != CellType::hexa && type != CellType::tetra) {
    reject(generator, std::string("type must be hexa or tetra (got ") + cell_type_name(type) + ")");
  }
  check_center(generator, center);
  check_node_budget(generator, arguments_text("cells", {cells[0], cells[1], cells[2]}),
                    double(cells[0] + 1.0) * (cells[1] + 1.0) * (cells[2] + 1.0));

  const BoxGrid grid{cells[0], cells[1], cells[2]};
  const Vec3 corner = center - 0.5 * size;
  const Vec3 step = size.cwiseQuotient(Vec3(grid.nx, grid.ny, grid.nz));
  Mesh mesh;
  mesh.points.reserve(grid.node_count());
  for (int k = 0; k <= grid.nz; ++k) {
    for (int j = 0; j <= grid.ny; ++j) {
      for (int i = 0; i <= grid.nx; ++i) {
        mesh.points.push_back(corner + step.cwiseProduct(Vec3(i, j, k)));
      }
    }
  }
  add_box_cells(grid, type, mesh.cells);
  add_box_node_sets(grid, mesh);
  return mesh;
}

Mesh make_ellipsoid_surface(const Vec3& radii, int subdivisions, const Vec3& center) {
  const char* generator = "make_ellipsoid_surface";
  check_radii(generator, radii);
  check_subdivisions(generator, subdivisions);
  check_center(generator, center);

  const Icosphere ico = make_icosphere(subdivisions);
  Mesh mesh;
  mesh.points.reserve(ico.unit.size());
  for (const Vec3& u : ico.unit) mesh.points.push_back(center + radii.cwiseProduct(u));
  mesh.cells.reserve(ico.triangles.size());
  for (const auto& [a, b, c] : ico.triangles) {
    mesh.cells.push_back(make_cell(CellType::triangle, {a, b, c}));
  }
  mesh.node_sets["top"] = {kNorthPole};
  mesh.node_sets["bottom"] = {kSouthPole};
  return mesh;
}

// Node 0 is the centre, then shell k = 1..layers (innermost first) holds the icosphere
// nodes at radius fraction k / layers. Between shells the quad faces of the wedges lie in
// planes through the centre (a linear image of a sphere's great-circle planes), so they
// are exactly planar.
Mesh make_ellipsoid_volume(const Vec3& radii, int subdivisions, int layers, const Vec3& center) {
  const char* generator = "make_ellipsoid_volume";
  check_radii(generator, radii);
  check_subdivisions(generator, subdivisions);
  check_at_least(generator, "layers", layers, 1);
  check_center(generator, center);
  check_node_budget(generator, arguments_text("subdivisions, layers", {subdivisions, layers}),
                    1.0 + layers * icosphere_node_count(subdivisions));

  const Icosphere ico = make_icosphere(subdivisions);
  const int per_shell = int(ico.unit.size());
  const auto node = [&](int shell, int v) { return 1 + (shell - 1) * per_shell + v; };
  Mesh mesh;
  mesh.points.reserve(1 + std::size_t(layers) * per_shell);
  mesh.points.push_back(center);
  for (int shell = 1; shell <= layers; ++shell) {
    const double fraction = double(shell) / layers;
    for (const Vec3& u : ico.unit) mesh.points.push_back(center + radii.cwiseProduct(u) * fraction);
  }
  mesh.cells.reserve(ico.triangles.size() * layers);
  for (const auto& [a, b, c] : ico.triangles) {
    mesh.cells.push_back(make_cell(CellType::tetra, {0, node(1, a), node(1, b), node(1, c)}));
  }
  // The outer triangle (outward) faces away from the inner one, as VTK wants of 0-1-2.
  for (int shell = 2; shell <= layers; ++shell) {
    for (const auto& [a, b, c] : ico.triangles) {
      mesh.cells.push_back(
          make_cell(CellType::wedge, {node(shell, a), node(shell, b), node(shell, c),
                                      node(shell - 1, a), node(shell - 1, b), node(shell - 1, c)}));
    }
  }
  mesh.node_sets["surface"] = index_range(node(layers, 0), per_shell);
  mesh.node_sets["top"] = {node(layers, kNorthPole)};
  mesh.node_sets["bottom"] = {node(layers, kSouthPole)};
  return mesh;
}

// A box grid of [-1, 1]^3 mapped onto the unit ball (the cube's faces onto the sphere, the
// interior smoothly; Nowell's mapping), then scaled: hexahedra of about the same size
// everywhere, unlike the shells, whose inner cells shrink and limit the stable time step.
Mesh make_ellipsoid_hexa(const Vec3& radii, int cells, const Vec3& center) {
  const char* generator = "make_ellipsoid_hexa";
  check_radii(generator, radii);
  check_at_least(generator, "hexahedra", cells, 2);
  if (cells % 2 != 0)
    reject(generator, "hexahedra must be even, so that the poles are nodes (got " +
                          std::to_string(cells) + ")");
  check_center(generator, center);
  Mesh mesh = make_box(Vec3::Constant(2.0), {cells, cells, cells}, CellType::hexa, Vec3::Zero());
  std::vector<int> surface;
  for (const char* face : {"left", "right", "front", "back", "bottom", "top"}) {
    const std::vector<int>& f = mesh.node_sets.at(face);
    surface.insert(surface.end(), f.begin(), f.end());
  }
  std::sort(surface.begin(), surface.end());
  surface.erase(std::unique(surface.begin(), surface.end()), surface.end());
  for (Vec3& p : mesh.points) {
    const Vec3 q = p.cwiseProduct(p);
    const Vec3 ball(p.x() * std::sqrt(1.0 - q.y() / 2 - q.z() / 2 + q.y() * q.z() / 3),
                    p.y() * std::sqrt(1.0 - q.z() / 2 - q.x() / 2 + q.z() * q.x() / 3),
                    p.z() * std::sqrt(1.0 - q.x() / 2 - q.y() / 2 + q.x() * q.y() / 3));
    p = center + radii.cwiseProduct(ball);
  }
  const int half = cells / 2, row = cells + 1;
  mesh.node_sets.clear();
  mesh.node_sets["surface"] = std::move(surface);
  mesh.node_sets["top"] = {(cells * row + half) * row + half};
  mesh.node_sets["bottom"] = {half * row + half};
  return mesh;
}

// Rings j = 0..along of `around` nodes (ring j at z = -length/2 + j * length/along), then
// the bottom and the top cap centres.
Mesh make_cylinder_surface(double radius, double length, int around, int along,
                           const Vec3& center) {
  const char* generator = "make_cylinder_surface";
  check_cylinder(generator, radius, length, around, along, center);
  check_node_budget(generator, arguments_text("around, along", {around, along}),
                    double(around) * (along + 1.0) + 2.0);

  const auto ring_node = [&](int j, int i) { return j * around + i % around; };
  const int bottom_centre = (along + 1) * around, top_centre = bottom_centre + 1;
  Mesh mesh;
  mesh.points.reserve(std::size_t(top_centre) + 1);
  for (int j = 0; j <= along; ++j) {
    const double z = -0.5 * length + length * j / along;
    for (int i = 0; i < around; ++i) {
      const double angle = 2.0 * std::numbers::pi * i / around;
      mesh.points.push_back(center + Vec3(radius * std::cos(angle), radius * std::sin(angle), z));
    }
  }
  mesh.points.push_back(center - Vec3(0.0, 0.0, 0.5 * length));
  mesh.points.push_back(center + Vec3(0.0, 0.0, 0.5 * length));
  const auto triangle = [&](int a, int b, int c) {
    mesh.cells.push_back(make_cell(CellType::triangle, {a, b, c}));
  };
  for (int j = 0; j < along; ++j) {
    for (int i = 0; i < around; ++i) {
      triangle(ring_node(j, i), ring_node(j, i + 1), ring_node(j + 1, i + 1));
      triangle(ring_node(j, i), ring_node(j + 1, i + 1), ring_node(j + 1, i));
    }
  }
  for (int i = 0; i < around; ++i) {
    triangle(bottom_centre, ring_node(0, i + 1), ring_node(0, i));
    triangle(top_centre, ring_node(along, i), ring_node(along, i + 1));
  }
  mesh.node_sets["side"] = index_range(0, bottom_centre);
  mesh.node_sets["bottom"] = index_range(0, around);
  mesh.node_sets["bottom"].push_back(bottom_centre);
  mesh.node_sets["top"] = index_range(along * around, around);
  mesh.node_sets["top"].push_back(top_centre);
  return mesh;
}

// The disk (see make_disk) copied at z = -length/2 + j * length/along, j = 0..along; node
// j * disk_size + d. The quad faces of the wedges are vertical, hence planar.
Mesh make_cylinder_volume(double radius, double length, int around, int along, int rings,
                          const Vec3& center) {
  const char* generator = "make_cylinder_volume";
  check_cylinder(generator, radius, length, around, along, center);
  check_at_least(generator, "rings", rings, 1);
  check_node_budget(generator, arguments_text("around, along, rings", {around, along, rings}),
                    (1.0 + double(rings) * around) * (along + 1.0));

  const Disk disk = make_disk(radius, around, rings);
  const int disk_size = int(disk.points.size());
  const auto node = [&](int layer, int d) { return layer * disk_size + d; };
  Mesh mesh;
  mesh.points.reserve(std::size_t(disk_size) * (along + 1));
  for (int j = 0; j <= along; ++j) {
    const double z = -0.5 * length + length * j / along;
    for (const Eigen::Vector2d& p : disk.points)
      mesh.points.push_back(center + Vec3(p.x(), p.y(), z));
  }
  mesh.cells.reserve(disk.triangles.size() * along);
  // Disk triangles face +z; reversed (a, c, b) on the lower layer they face away from the
  // upper layer, as VTK wants of wedge triangle 0-1-2.
  for (int j = 0; j < along; ++j) {
    for (const auto& [a, b, c] : disk.triangles) {
      mesh.cells.push_back(make_cell(
          CellType::wedge,
          {node(j, a), node(j, c), node(j, b), node(j + 1, a), node(j + 1, c), node(j + 1, b)}));
    }
  }
  mesh.node_sets["bottom"] = index_range(node(0, 0), disk_size);
  mesh.node_sets["top"] = index_range(node(along, 0), disk_size);
  auto& side = mesh.node_sets["side"];
  for (int j = 0; j <= along; ++j) {
    for (int m = 0; m < disk.rim_count; ++m) side.push_back(node(j, disk.rim_begin + m));
  }
  return mesh;
}

}  // namespace phymul
