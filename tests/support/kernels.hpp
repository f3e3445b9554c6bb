// The library's kernels on one obstacle, volume or pressure load with its own schedule: the
// calls the tests make, written with the entry points the library runs (a model's items,
// moved by the controls).
#pragma once

#include <span>
#include <vector>

#include "constraints/constraints.hpp"
#include "constraints/contact.hpp"
#include "forces/pressure.hpp"

namespace phymul {

// Signed distance and outward normal of x to the obstacle at load_time, its own motion applied.
inline SurfaceDistance obstacle_distance(const RigidObstacle& obstacle, const Vec3& x,
                                         double load_time) {
  return obstacle_distance(obstacle, obstacle.motion, x, load_time);
}

// The closest point of the obstacle's surface to x: x - distance * normal.
inline Vec3 closest_surface_point(const RigidObstacle& obstacle, const Vec3& x, double load_time) {
  const SurfaceDistance s = obstacle_distance(obstacle, x, load_time);
  return x - s.distance * s.normal;
}

// apply_contacts for this obstacle alone, moved by its own motion.
inline void project_obstacle(const RigidObstacle& obstacle, std::span<const Vec3> inverse_mass,
                             std::span<Vec3> x, double load_time) {
  Model model;
  model.obstacles = {obstacle};
  model.inverse_mass.assign(inverse_mass.begin(), inverse_mass.end());
  Controls controls;
  controls.obstacle_motion = {obstacle.motion};
  apply_contacts(model, controls, x, load_time);
}

// project_volume towards the constraint's own target_volume.
inline double project_volume(const VolumeConstraint& c, std::span<const Vec3> inverse_mass,
                             std::span<Vec3> x, std::span<Vec3> grad) {
  return project_volume(c, inverse_mass, x, grad, c.target_volume);
}

// add_pressure with the load's own pressure at load_time.
inline void add_pressure_forces(const PressureLoad& load, std::span<const Vec3> x,
                                std::span<Vec3> f, double load_time) {
  add_pressure(load, load.pressure.at(load_time).x(), x, f);
}

}  // namespace phymul
