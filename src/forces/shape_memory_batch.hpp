// The polar shape-memory pass, batched: kShapeMemoryLanes memory nodes of equal neighbour
// count at a time, their fit, warm Newton rotation turns, pull and exact reaction computed in
// vector lanes (structure of arrays). A lane whose Newton turns would not settle the rotation
// as the scalar path does redoes its node on the scalar path (add_polar_node_forces).
#pragma once

#include <array>
#include <span>

#include "model/shape_memory_rest.hpp"
#include "phymul/model.hpp"

namespace phymul {

// The pass of a centred memory node k: the pull K (g - x_i) and, with m.reaction, -f_i / n
// on each neighbour (the exact reaction: the rotation's term vanishes with the rest offset).
// Returns its energy; leaves its rotation as it is.
double add_centred_node_forces(const ShapeMemory& m, int k, std::span<const Vec3> x,
                               std::span<Vec3> f);
// The same for the centred memory nodes ks[0, count) of one block, in that order; runs of
// consecutive global ids as a stencil (m.centred_on_stencil). The same forces up to their
// order of summation.
double add_centred_forces(const ShapeMemory& m, const int* ks, int count, std::span<const Vec3> x,
                          std::span<Vec3> f);

// The scalar pass of memory node k: adds its forces (N) to f, returns its energy (J).
double add_polar_node_forces(const ShapeMemory& m, int k, std::span<const Vec3> rest,
                             std::span<const Vec3> x, std::span<Eigen::Quaterniond> rotations,
                             std::span<Vec3> f);

// The pass of the memory nodes ks (equal neighbour counts, all with a normal pair or none), lane by
// lane in their order as far as the forces are concerned; returns their energy. batched[l]: lane l
// was computed in the lanes (false: it fell back to the scalar path).
double add_polar_batch_forces(const ShapeMemory& m, const std::array<int, kShapeMemoryLanes>& ks,
                              std::span<const Vec3> rest, std::span<const Vec3> x,
                              std::span<Eigen::Quaterniond> rotations, std::span<Vec3> f,
                              std::array<bool, kShapeMemoryLanes>* batched = nullptr);

// Two batches, ks[0, lanes) then ks[lanes, 2 lanes), as two calls of add_polar_batch_forces
// would do them (the same forces, rotations and energy, added to `energy` batch by batch), their
// rotations' turns side by side.
void add_polar_batch_pair_forces(const ShapeMemory& m, const int* ks, std::span<const Vec3> rest,
                                 std::span<const Vec3> x, std::span<Eigen::Quaterniond> rotations,
                                 std::span<Vec3> f, double& energy);

}  // namespace phymul
