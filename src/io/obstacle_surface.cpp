#include "io/obstacle_surface.hpp"

#include <cmath>
#include <numbers>

#include "phymul/vtk.hpp"

namespace phymul {
namespace {

using Shape = RigidObstacle::Shape;

constexpr int kAround = 32;  // segments around an axis: smooth at picture sizes

// Two unit vectors completing `axis` to a right-handed frame.
std::pair<Vec3, Vec3> frame_of(const Vec3& axis) {
  const Vec3 trial = std::abs(axis.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 u = axis.cross(trial).normalized();
  return {u, axis.cross(u)};
}

void add_triangle(Mesh& mesh, int a, int b, int c) {
  Cell cell;
  cell.type = CellType::triangle;
  cell.nodes[0] = a, cell.nodes[1] = b, cell.nodes[2] = c;
  mesh.cells.push_back(cell);
}

// A surface of revolution about `axis` through `base`: the profile is a list of (position
// along the axis, distance from it); a zero distance at either end is a pole. Triangles face
// outwards when the profile runs along +axis.
void add_lathe(Mesh& mesh, const Vec3& base, const Vec3& axis,
               const std::vector<std::pair<double, double>>& profile) {
  const auto [u, w] = frame_of(axis);
  std::vector<int> ring_start;
  for (const auto& [along, radius] : profile) {
    ring_start.push_back(int(mesh.points.size()));
    const int count = radius == 0.0 ? 1 : kAround;
    for (int k = 0; k < count; ++k) {
      const double angle = 2.0 * std::numbers::pi * k / kAround;
      mesh.points.push_back(base + along * axis +
                            radius * (std::cos(angle) * u + std::sin(angle) * w));
    }
  }
  for (size_t r = 0; r + 1 < profile.size(); ++r) {
    const int a = ring_start[r], b = ring_start[r + 1];
    const bool pole_a = profile[r].second == 0.0, pole_b = profile[r + 1].second == 0.0;
    for (int k = 0; k < kAround; ++k) {
      const int k1 = (k + 1) % kAround;
      if (pole_a) {
        add_triangle(mesh, a, b + k1, b + k);
      } else if (pole_b) {
        add_triangle(mesh, a + k, a + k1, b);
      } else {
        add_triangle(mesh, a + k, b + k1, b + k);
        add_triangle(mesh, a + k, a + k1, b + k1);
      }
    }
  }
}

// Quarter circle of `radius` about `centre` along the axis, from the pole (`sign` -1: below
// the centre, +1: above) to the equator, or back.
std::vector<std::pair<double, double>> cap(double centre, double radius, int sign) {
  constexpr int kRings = 8;
  std::vector<std::pair<double, double>> out;
  for (int i = 0; i <= kRings; ++i) {
    const double phi = 0.5 * std::numbers::pi * (sign < 0 ? i : kRings - i) / kRings;
    out.push_back({centre + sign * radius * std::cos(phi), radius * std::sin(phi)});
  }
  return out;
}

void add_plane(Mesh& mesh, const Vec3& point, const Vec3& normal, const Vec3& centre, double half) {
  const auto [u, w] = frame_of(normal);
  const Vec3 middle = centre - (centre - point).dot(normal) * normal;
  const int first = int(mesh.points.size());
  for (const auto& [a, b] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}})
    mesh.points.push_back(middle + half * (a * u + b * w));
  add_triangle(mesh, first, first + 1, first + 2);
  add_triangle(mesh, first, first + 2, first + 3);
}

void add_obstacle(Mesh& mesh, const RigidObstacle& o, const Vec3& base, const Vec3& centre,
                  double diagonal) {
  const double r = o.radius;
  std::vector<std::pair<double, double>> profile;
  switch (o.shape) {
    case Shape::plane:
      add_plane(mesh, base, o.axis, centre, 0.6 * diagonal);
      return;
    case Shape::sphere:  // the two caps share the equator
      profile = cap(0.0, r, -1);
      profile.pop_back();
      for (auto& p : cap(0.0, r, 1)) profile.push_back(p);
      break;
    case Shape::capsule:
      profile = cap(0.0, r, -1);
      for (auto& p : cap(o.length, r, 1)) profile.push_back(p);
      break;
    case Shape::probe:  // open base, as the shape: cut a diagonal back from the tip
      profile = {{o.length + r - diagonal, r}};
      for (auto& p : cap(o.length, r, 1)) profile.push_back(p);
      break;
  }
  add_lathe(mesh, base, o.axis, profile);
}

}  // namespace

Mesh obstacle_surfaces(std::span<const RigidObstacle> obstacles, std::span<const Schedule> motions,
                       double load_time, const Vec3& lo, const Vec3& hi,
                       std::vector<int>& cell_obstacle) {
  Mesh mesh;
  cell_obstacle.clear();
  const Vec3 centre = 0.5 * (lo + hi);
  const double diagonal = std::max((hi - lo).norm(), 1e-3);
  for (size_t k = 0; k < obstacles.size(); ++k) {
    const RigidObstacle& o = obstacles[k];
    const Schedule& motion = motions.empty() ? o.motion : motions[k];
    add_obstacle(mesh, o, o.point + motion.at(load_time), centre, diagonal);
    cell_obstacle.resize(mesh.cells.size(), int(k));
  }
  return mesh;
}

void write_obstacle_surfaces(const std::filesystem::path& path,
                             std::span<const RigidObstacle> obstacles,
                             std::span<const Schedule> motions, double load_time,
                             std::span<const Vec3> x, VtuEncoding encoding) {
  const auto [lo, hi] = bounding_box(x);
  std::vector<int> owner;
  const Mesh surfaces = obstacle_surfaces(obstacles, motions, load_time, lo, hi, owner);
  const CellField cells[] = {{"obstacle", owner}};
  write_vtu(path, surfaces.points, surfaces.cells, {}, cells, encoding);
}

}  // namespace phymul
