#include <fmt/format.h>
#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>
#include <unordered_map>

#include "phymul/meshing.hpp"

namespace phymul {
namespace {

// Gmsh keeps one global model: one mesher call at a time.
std::mutex gmsh_mutex;

struct GmshSession {
  GmshSession() {
    gmsh::initialize(0, nullptr, false);
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::logger::start();  // its messages, for ours when it fails
    gmsh::model::add("phymul");
  }
  ~GmshSession() { gmsh::finalize(); }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;
};

// The surface as one discrete Gmsh surface bounding one volume; nodes tagged 1..n in order.
void add_surface(const Mesh& surface) {
  const int s = gmsh::model::addDiscreteEntity(2);
  std::vector<std::size_t> tags(surface.points.size());
  std::vector<double> coords;
  coords.reserve(3 * surface.points.size());
  for (size_t i = 0; i < surface.points.size(); ++i) {
    tags[i] = i + 1;
    for (int a = 0; a < 3; ++a) coords.push_back(surface.points[i][a]);
  }
  gmsh::model::mesh::addNodes(2, s, tags, coords);
  std::vector<std::size_t> corners;
  for (const Cell& c : surface.cells)
    for (int k = 0; k < 3; ++k) corners.push_back(std::size_t(c.nodes[size_t(k)]) + 1);
  gmsh::model::mesh::addElementsByType(s, 2, {}, corners);  // 2: three-node triangles
  // The volume the discrete surface bounds, its triangles kept (no reparametrisation).
  const int loop = gmsh::model::geo::addSurfaceLoop({s});
  gmsh::model::geo::addVolume({loop});
  gmsh::model::geo::synchronize();
}

Mesh collect(const Mesh& surface) {
  std::vector<std::size_t> tags, tetra_tags, tetra_nodes;
  std::vector<double> coords, params;
  gmsh::model::mesh::getNodes(tags, coords, params, -1, -1, true, false);
  gmsh::model::mesh::getElementsByType(4, tetra_tags, tetra_nodes);  // 4: four-node tetrahedra
  if (tetra_tags.empty()) throw MeshError("the mesher made no tetrahedron");
  Mesh out;
  out.points = surface.points;  // tags 1..n: the surface's points, first and unchanged
  std::unordered_map<std::size_t, int> index;
  for (size_t i = 0; i < surface.points.size(); ++i) index[i + 1] = int(i);
  for (size_t k = 0; k < tags.size(); ++k)
    if (!index.contains(tags[k])) {
      index[tags[k]] = int(out.points.size());
      out.points.emplace_back(coords[3 * k], coords[3 * k + 1], coords[3 * k + 2]);
    }
  for (size_t e = 0; e < tetra_tags.size(); ++e) {
    Cell c;
    c.type = CellType::tetra;
    for (int k = 0; k < 4; ++k) c.nodes[size_t(k)] = index.at(tetra_nodes[4 * e + size_t(k)]);
    if (cell_measure(out.points, c) < 0.0) std::swap(c.nodes[0], c.nodes[1]);
    out.cells.push_back(c);
  }
  return out;
}

double dihedral_min(const std::array<Vec3, 4>& p) {
  // The angle at each edge between the two faces that share it, from their outward normals.
  static constexpr int faces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::array<Vec3, 4> n;
  for (int f = 0; f < 4; ++f)
    n[f] = (p[faces[f][1]] - p[faces[f][0]]).cross(p[faces[f][2]] - p[faces[f][0]]).normalized();
  double smallest = 180.0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b)
      smallest = std::min(smallest, 180.0 - std::acos(std::clamp(n[a].dot(n[b]), -1.0, 1.0)) *
                                                180.0 / std::numbers::pi);
  return smallest;
}

double radius_edge(const std::array<Vec3, 4>& p) {
  const Vec3 a = p[1] - p[0], b = p[2] - p[0], c = p[3] - p[0];
  const double six_volume = a.dot(b.cross(c));
  const Vec3 centre =
      (a.squaredNorm() * b.cross(c) + b.squaredNorm() * c.cross(a) + c.squaredNorm() * a.cross(b)) /
      (2.0 * six_volume);
  double shortest = INFINITY;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) shortest = std::min(shortest, (p[i] - p[j]).norm());
  return centre.norm() / shortest;
}

// Gmsh's last error (its API throws without a message), else its last message.
std::string last_gmsh_error() {
  std::vector<std::string> log;
  gmsh::logger::get(log);
  for (auto it = log.rbegin(); it != log.rend(); ++it)
    if (it->starts_with("Error")) return *it;
  return log.empty() ? "Gmsh failed" : log.back();
}

}  // namespace

Mesh fill_with_tetrahedra(const Mesh& surface, double edge) {
  if (!(edge > 0.0) || !std::isfinite(edge))
    throw MeshError(fmt::format("the tetrahedra's edge must be > 0 m (got {})", edge));
  std::lock_guard lock(gmsh_mutex);
  GmshSession session;
  try {
    add_surface(surface);
  } catch (...) {
    throw MeshError(fmt::format("Gmsh refused the surface: {}", last_gmsh_error()));
  }
  // `edge` sizes the inside, not the surface's triangles: a fine surface grades out to it
  // (a 20,480-triangle ellipsoid: 47k tetrahedra, not the 238k that sizes grown from the
  // boundary give).
  gmsh::option::setNumber("Mesh.MeshSizeMax", edge);
  gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
  gmsh::option::setNumber("Mesh.Algorithm3D", 1);  // Delaunay
  // The optimiser takes every tetrahedron of quality below 0.5 (default 0.3): the grading's
  // slivers go (smallest dihedral angle there 0.7 -> 9.4 degrees) for 0.6 s more.
  gmsh::option::setNumber("Mesh.Optimize", 1);
  gmsh::option::setNumber("Mesh.OptimizeThreshold", 0.5);
  try {
    gmsh::model::mesh::generate(3);
  } catch (...) {
    throw MeshError(
        fmt::format("the surface could not be filled with tetrahedra: {}", last_gmsh_error()));
  }
  return collect(surface);
}

TetraQuality tetra_quality(const Mesh& mesh) {
  TetraQuality q;
  q.min_dihedral_deg = 180.0;
  for (const Cell& c : mesh.cells) {
    if (c.type != CellType::tetra) continue;
    const std::array<Vec3, 4> p{mesh.points[size_t(c.nodes[0])], mesh.points[size_t(c.nodes[1])],
                                mesh.points[size_t(c.nodes[2])], mesh.points[size_t(c.nodes[3])]};
    ++q.tetrahedra;
    q.min_dihedral_deg = std::min(q.min_dihedral_deg, dihedral_min(p));
    q.max_radius_edge = std::max(q.max_radius_edge, radius_edge(p));
  }
  return q;
}

}  // namespace phymul
