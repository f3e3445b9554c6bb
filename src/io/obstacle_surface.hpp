// Triangulated surfaces of the rigid obstacles at an instant, for the result files: the
// obstacles are analytic shapes (constraints/contact.hpp) and would otherwise be invisible in
// the pictures and in ParaView.
#pragma once

#include <filesystem>
#include <span>

#include "phymul/mesh.hpp"
#include "phymul/model.hpp"
#include "phymul/vtk.hpp"

namespace phymul {

// The surfaces of `obstacles` at load_time, their motion applied (`motions`, one per obstacle:
// a Data's controls; empty: each obstacle's own), as one triangle mesh;
// cell_obstacle gets each triangle's obstacle index. Unbounded shapes are cut to the
// region the model occupies, `lo`..`hi` (m, its bounding box): a plane becomes a square
// 1.2 box diagonals wide, centred where the box's centre projects onto it, and the
// endorectal probe's open base a cylinder reaching back that diagonal from its tip.
Mesh obstacle_surfaces(std::span<const RigidObstacle> obstacles, std::span<const Schedule> motions,
                       double load_time, const Vec3& lo, const Vec3& hi,
                       std::vector<int>& cell_obstacle);

// Those surfaces, cut to the bounding box of the body's positions x, as a .vtu (cell field
// `obstacle`) at `path`, written atomically: the frame that goes beside the body's.
void write_obstacle_surfaces(const std::filesystem::path& path,
                             std::span<const RigidObstacle> obstacles,
                             std::span<const Schedule> motions, double load_time,
                             std::span<const Vec3> x, VtuEncoding encoding = VtuEncoding::ascii);

}  // namespace phymul
