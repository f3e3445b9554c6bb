// The polar shape-memory pass in single precision (issue 6): kShapeMemorySingleLanes memory
// nodes at a time in float lanes, as the double kernel (shape_memory_batch.cpp) does them in
// four double lanes. Positions stay double: each neighbour's offset x_j - x_i (and X_j - X_i) is
// taken in double and only then rounded, so nodes far from the origin lose nothing. Rotations
// stay double in State (rounded at the batch's entry, renormalised in double at its exit), and
// forces and energy are added into double sums. A lane whose float Newton turns do not settle,
// or whose Hessian is too ill-conditioned for float, redoes its node on the double scalar path.
#pragma once

#include <array>
#include <span>

#include "phymul/model.hpp"

namespace phymul {

inline constexpr int kShapeMemorySingleLanes = 8;

// The pass of memory nodes ks[0, used) (1 <= used <= kShapeMemorySingleLanes; equal neighbour
// counts, all with a normal pair or none) in float lanes; forces (N) added to f lane by lane
// in their order, their energy (J) returned. batched[l]: lane l was computed in float (false:
// it fell back to the double scalar path).
double add_polar_batch_forces_single(const ShapeMemory& m, const int* ks, int used,
                                     std::span<const Vec3> rest, std::span<const Vec3> x,
                                     std::span<Eigen::Quaterniond> rotations, std::span<Vec3> f,
                                     std::array<bool, kShapeMemorySingleLanes>* batched = nullptr);

// add_shape_memory_forces with the polar batches in float lanes: the double batches of four
// (plan_polar_batches) paired into batches of eight where their neighbour counts agree, alone
// where not; the nodes left out of batches, and frame mode, go the double way. The order of
// the sums is the model's, whatever the number of threads.
double add_shape_memory_forces_single(const ShapeMemory& memory, std::span<const Vec3> rest,
                                      std::span<const Vec3> x,
                                      std::span<Eigen::Quaterniond> rotations, std::span<Vec3> f);

}  // namespace phymul
