// Quality of a triangle surface (the remesher's report) and the volume it encloses.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

#include "phymul/meshing.hpp"

namespace phymul {

SurfaceQuality surface_quality(const Mesh& surface) {
  SurfaceQuality q;
  q.min_angle_deg = 180.0;
  q.edge_min = INFINITY;
  std::set<std::pair<int, int>> seen;
  double edge_sum = 0.0;
  for (const Cell& c : surface.cells) {
    if (c.type != CellType::triangle) continue;
    ++q.triangles;
    std::array<Vec3, 3> p;
    for (size_t k = 0; k < 3; ++k) p[k] = surface.points[size_t(c.nodes[k])];
    std::array<double, 3> l{};
    for (size_t k = 0; k < 3; ++k) {
      l[k] = (p[(k + 1) % 3] - p[k]).norm();
      const auto key = std::minmax(c.nodes[k], c.nodes[(k + 1) % 3]);
      if (!seen.insert({key.first, key.second}).second) continue;
      q.edge_min = std::min(q.edge_min, l[k]);
      q.edge_max = std::max(q.edge_max, l[k]);
      edge_sum += l[k];
    }
    for (size_t k = 0; k < 3; ++k) {
      const Vec3 u = p[(k + 1) % 3] - p[k], v = p[(k + 2) % 3] - p[k];
      const double angle = std::atan2(u.cross(v).norm(), u.dot(v)) * 180.0 / std::numbers::pi;
      q.min_angle_deg = std::min(q.min_angle_deg, angle);
    }
    // Verdict's aspect ratio: longest edge over 2 sqrt(3) times the inradius.
    const double area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
    const double perimeter = l[0] + l[1] + l[2];
    const double longest = std::max({l[0], l[1], l[2]});
    q.max_aspect = std::max(
        q.max_aspect, area > 0.0 ? longest * perimeter / (4.0 * std::sqrt(3.0) * area) : INFINITY);
  }
  if (seen.empty()) q.edge_min = 0.0;
  q.edge_mean = seen.empty() ? 0.0 : edge_sum / double(seen.size());
  return q;
}

double enclosed_volume(const Mesh& surface) {
  if (surface.points.empty()) return 0.0;
  const Vec3 origin = surface.points.front();  // near the surface: less cancellation
  double six = 0.0;
  for (const Cell& c : surface.cells) {
    if (c.type != CellType::triangle) continue;
    const Vec3 a = surface.points[size_t(c.nodes[0])] - origin;
    const Vec3 b = surface.points[size_t(c.nodes[1])] - origin;
    const Vec3 d = surface.points[size_t(c.nodes[2])] - origin;
    six += a.dot(b.cross(d));
  }
  return six / 6.0;
}

}  // namespace phymul
