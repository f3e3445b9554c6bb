// Contact with rigid analytic obstacles, enforced by projection (DESIGN 2.3 step 4).
#pragma once

#include <span>

#include "phymul/model.hpp"

namespace phymul {

// Where a point stands relative to an obstacle's surface.
struct SurfaceDistance {
  double distance = 0.0;        // m, signed: negative inside the shape
  Vec3 normal = Vec3::UnitZ();  // unit, outward, at the closest surface point
};

// Signed distance and outward normal of x to the obstacle at load_time (its motion applied).
// On the medial axis (a sphere's centre, a capsule's segment) the normal is any direction
// perpendicular to the axis: every one leads to a closest point.
SurfaceDistance obstacle_distance(const RigidObstacle& obstacle, const Vec3& x, double load_time);

// The closest point of the obstacle's surface to x: x - distance * normal.
Vec3 closest_surface_point(const RigidObstacle& obstacle, const Vec3& x, double load_time);

// Moves every affected node that violates the obstacle (inside it; outside it when
// keep_inside) onto its surface, only along the node's free axes. A fully free node goes to
// the closest surface point; a partly held one along the normal restricted to its free axes.
void project_obstacle(const RigidObstacle& obstacle, std::span<const Vec3> inverse_mass,
                      std::span<Vec3> x, double load_time);

// Every obstacle of the model, in order.
void apply_contacts(const Model& model, std::span<Vec3> x, double load_time);

}  // namespace phymul
