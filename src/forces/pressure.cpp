#include "forces/pressure.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace phymul {

void add_pressure(const PressureLoad& load, double p, std::span<const Vec3> x, std::span<Vec3> f) {
  if (p == 0.0) return;
  for (const Triangle& t : load.faces) {
    // (b - a) x (c - a) is twice the area vector: each node takes a third of p * area.
    const Vec3 twice_area = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
    const Vec3 node_force = (-p / 6.0) * twice_area;
    for (int i : t) f[i] += node_force;
  }
}

std::vector<Triangle> faces_in_cylinder(const Model& model, int component, const Vec3& axis_point,
                                        const Vec3& axis_direction, double radius) {
  if (component < 0 || component >= int(model.components.size()))
    throw std::invalid_argument(
        fmt::format("faces_in_cylinder: component {} is out of range ({} components)", component,
                    model.components.size()));
  if (!(axis_direction.norm() > 0.0) || !(radius > 0.0))
    throw std::invalid_argument("faces_in_cylinder: needs a non-zero axis and a radius > 0 m");
  const Vec3 axis = axis_direction.normalized();
  std::vector<Triangle> selected;
  for (const Triangle& t : model.components.at(size_t(component)).boundary) {
    const Vec3 centroid =
        (model.rest_position[t[0]] + model.rest_position[t[1]] + model.rest_position[t[2]]) / 3.0;
    const Vec3 r = centroid - axis_point;
    if ((r - r.dot(axis) * axis).norm() <= radius) selected.push_back(t);
  }
  return selected;
}

}  // namespace phymul
