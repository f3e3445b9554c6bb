// Isotropic surface remeshing (Botsch and Kobbelt, "A remeshing approach to multiresolution
// modeling", SGP 2004): split edges above 4/3 of the target, collapse those below 4/5, flip
// towards valence 6, relax tangentially, project back onto the input. Every operation keeps the
// surface closed, manifold and consistently oriented, so the result needs no repair.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "mesh/nearest_triangle.hpp"
#include "mesh/remesh_ops.hpp"
#include "mesh/surface_check.hpp"
#include "phymul/meshing.hpp"

namespace phymul {
namespace {

// Fewer triangles than an icosahedron cannot stand for a closed organ; more than this many
// is a mistaken unit, not a model.
constexpr double kMinTriangles = 20.0, kMaxTriangles = 4e6;
constexpr int kIterations = 10;

std::vector<Triangle> triangles_of(const Mesh& m) {
  std::vector<Triangle> t;
  t.reserve(m.cells.size());
  for (const Cell& c : m.cells) {
    if (c.type != CellType::triangle)
      throw MeshError(
          fmt::format("remeshing takes triangles only (got a {} cell)", cell_type_name(c.type)));
    t.push_back({c.nodes[0], c.nodes[1], c.nodes[2]});
  }
  return t;
}

double area_of(const Mesh& m) {
  double area = 0.0;
  for (const Cell& c : m.cells) area += cell_measure(m.points, c);
  return area;
}

// Every edge run once each way: closed, manifold and consistently oriented, which the local
// operations need. (Crossing triangles and inside-out surfaces are check_closed_surface's
// to find, as the readers do; done again here it would cost more than the remeshing.)
void check_closed_and_oriented(const std::vector<Triangle>& t, size_t points) {
  std::unordered_map<std::uint64_t, int> runs;  // directed edge a -> b: how many triangles
  runs.reserve(3 * t.size());
  for (const Triangle& c : t)
    for (size_t k = 0; k < 3; ++k) {
      const int a = c[k], b = c[(k + 1) % 3];
      if (a < 0 || b < 0 || size_t(a) >= points || size_t(b) >= points || a == b)
        throw MeshError(
            fmt::format("remeshing needs a closed surface: a triangle has corners "
                        "{} and {} of {} points",
                        a, b, points));
      ++runs[std::uint64_t(a) << 32 | std::uint32_t(b)];
    }
  for (const auto& [edge, count] : runs) {
    const int a = int(edge >> 32), b = int(edge & 0xffffffffu);
    const auto back = runs.find(std::uint64_t(b) << 32 | std::uint32_t(a));
    if (count != 1 || back == runs.end() || back->second != 1)
      throw MeshError(fmt::format(
          "remeshing needs a closed, manifold, consistently oriented surface (check_closed_surface "
          "repairs the orientation): edge {}-{} is run by {} triangle(s) one way and {} the other",
          a, b, count, back == runs.end() ? 0 : back->second));
  }
}

// The edge range for a surface of this area, from the triangle counts allowed.
std::string edge_range(double area) {
  const double per = std::sqrt(3.0) / 4.0;  // area of an equilateral triangle of edge 1
  return fmt::format("the edge must be in [{:.3g}, {:.3g}] mm ({:g} to {:g} triangles)",
                     std::sqrt(area / (per * kMaxTriangles)) * 1e3,
                     std::sqrt(area / (per * kMinTriangles)) * 1e3, kMinTriangles, kMaxTriangles);
}

// The triangle count an edge gives, from the area of equilateral triangles of that edge.
void check_edge(const Mesh& m, double edge) {
  if (!(edge > 0.0) || !std::isfinite(edge))
    throw MeshError(fmt::format("the remeshing edge must be > 0 m (got {})", edge));
  const double area = area_of(m);
  const double count = area / (std::sqrt(3.0) / 4.0 * edge * edge);
  if (count < kMinTriangles || count > kMaxTriangles)
    throw MeshError(
        fmt::format("the remeshing edge {:g} mm does not fit this surface (area {:.3g} "
                    "mm^2): it would take about {:.0f} triangles; {}",
                    edge * 1e3, area * 1e6, count, edge_range(area)));
}

Mesh to_mesh(const remesh::Work& w) {
  Mesh m;
  std::vector<int> index(w.x.size(), -1);
  for (const Triangle& t : w.t) {
    if (t[0] < 0) continue;
    Cell c;
    c.type = CellType::triangle;
    for (size_t k = 0; k < 3; ++k) {
      int& i = index[size_t(t[k])];
      if (i < 0) {
        i = int(m.points.size());
        m.points.push_back(w.x[size_t(t[k])]);
      }
      c.nodes[k] = i;
    }
    m.cells.push_back(c);
  }
  return m;
}

// Largest distance from points of `a` (corners and triangle centroids) to surface `b`.
double one_way(const Mesh& a, const NearestTriangle& b) {
  double d = 0.0;
  for (const Vec3& p : a.points) d = std::max(d, b.nearest(p).distance);
  for (const Cell& c : a.cells) {
    const Vec3 centroid = (a.points[size_t(c.nodes[0])] + a.points[size_t(c.nodes[1])] +
                           a.points[size_t(c.nodes[2])]) /
                          3.0;
    d = std::max(d, b.nearest(centroid).distance);
  }
  return d;
}

}  // namespace

Remeshed remesh_surface(const Mesh& closed_surface, double edge) {
  const Mesh& input = closed_surface;
  const std::vector<Triangle> input_triangles = triangles_of(input);
  if (input.cells.empty()) throw MeshError("remeshing needs a surface; this one has no triangle");
  check_closed_and_oriented(input_triangles, input.points.size());
  if (!(enclosed_volume(input) > 0.0))
    throw MeshError(
        "remeshing needs an outward surface; this one is inside out or flat "
        "(check_closed_surface turns it outward)");
  check_edge(input, edge);
  const NearestTriangle target(input.points, input_triangles);
  remesh::Work w{input.points, input_triangles};
  for (int i = 0; i < kIterations; ++i) {
    remesh::split_long(w, 4.0 / 3.0 * edge);
    remesh::collapse_short(w, 4.0 / 5.0 * edge, 4.0 / 3.0 * edge);
    remesh::flip_to_valence(w);
    remesh::compact(w);
    remesh::relax(w);
    for (Vec3& p : w.x) p = target.nearest(p).point;
  }
  Remeshed out;
  out.surface = to_mesh(w);
  const SurfaceCheck result = check_closed_surface(out.surface);
  if (!result.problems.empty())
    throw MeshError(fmt::format("remeshing to {:g} mm did not give a closed surface: {}",
                                edge * 1e3, fmt::join(result.problems, "; ")));
  out.quality = surface_quality(out.surface);
  if (double(out.quality.triangles) < kMinTriangles)  // the shape is too thin for the edge
    throw MeshError(fmt::format(
        "the remeshing edge {:g} mm is too long for this surface: it left {} triangles; {}",
        edge * 1e3, out.quality.triangles, edge_range(area_of(input))));
  const NearestTriangle back(out.surface.points, triangles_of(out.surface));
  out.deviation = std::max(one_way(out.surface, target), one_way(input, back));
  out.volume_before = enclosed_volume(input);
  out.volume_after = enclosed_volume(out.surface);
  return out;
}

}  // namespace phymul
