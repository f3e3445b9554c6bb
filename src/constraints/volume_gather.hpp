// The volume gradient gathered node by node from the triangles around it (index_volume_faces),
// shared by the single surface's projection (volume.cpp) and the joint one
// (coupled_volume.cpp).
#pragma once

#include <array>
#include <span>

#include "phymul/model.hpp"

namespace phymul {

// Whether finalize indexed c's triangles around its nodes (else: the triangles' scatter).
inline bool gathered(const VolumeConstraint& c) {
  return c.incident_start.size() == c.nodes.size() + 1;
}

// 6 dV/dx at c.nodes[k], summed over its triangles in the order the triangles' scatter adds
// them (the same bits), so that each node is one thread's: parallel and independent of the
// thread count; no zeroing pass, no stores but the result. Plain pointers, which the stores
// into the gradient cannot move.
struct FaceGather {
  const int* __restrict start;
  const std::array<int, 2>* __restrict pair;
  const Vec3* __restrict x;
  FaceGather(const VolumeConstraint& c, std::span<const Vec3> positions)
      : start(c.incident_start.data()), pair(c.incident.data()), x(positions.data()) {}
  [[gnu::always_inline]] Vec3 six_gradient_at(int k) const {
    Vec3 g = Vec3::Zero();
    for (int e = start[k]; e < start[k + 1]; ++e) g += x[pair[e][0]].cross(x[pair[e][1]]);
    return g;
  }
};

}  // namespace phymul
