// The geometry of a shape-memory neighbourhood (DESIGN 2.1): its centroid, normals and the
// paper's local frame. The rest memory (model/shape_memory_rest.cpp) and the force passes
// (forces/shape_memory.cpp) read them alike. Static, each file its own copy: GCC contracts
// a * b + c into fused multiply-adds as inlining exposes them, and an `inline` function is
// inlined where a static one was not, which moved the scalar pass's results by round-off.
#pragma once

#include <array>
#include <cassert>
#include <span>

#include "phymul/model.hpp"

namespace phymul {

[[maybe_unused]] static Vec3 centroid(std::span<const int> ids, std::span<const Vec3> p) {
  Vec3 g = Vec3::Zero();
  for (int j : ids) g += p[j];
  return g / double(ids.size());
}

// Normal of an ordered ring around its centroid g: sum of consecutive cross products,
// closed when the ring is a cycle. Consistent with the ring's orientation.
[[maybe_unused]] static Vec3 ring_normal(std::span<const int> ring, std::span<const Vec3> p,
                                         const Vec3& g) {
  Vec3 n = Vec3::Zero();
  for (size_t k = 0; k + 1 < ring.size(); ++k) n += (p[ring[k]] - g).cross(p[ring[k + 1]] - g);
  if (ring.size() > 2) n += (p[ring.back()] - g).cross(p[ring.front()] - g);
  return n;
}

[[maybe_unused]] static Vec3 pair_normal(std::span<const int> nb, const std::array<int, 2>& pair,
                                         std::span<const Vec3> p, const Vec3& g) {
  return (p[nb[pair[0]]] - g).cross(p[nb[pair[1]]] - g);
}

// Zero for the nodes without a normal pair (ShapeMemory::framed).
[[maybe_unused]] static double normal_weight(const ShapeMemory& m, int k) {
  const int f = m.framed.find(k);
  return f < 0 ? 0.0 : m.normal_weight[size_t(f)];
}

// Memory node k of a volume, a framed one: its callers read it only where the node has a
// normal pair (weight > 0) or in frame mode, which frames every volume node.
[[maybe_unused]] static const std::array<int, 2>& frame_pair(const ShapeMemory& m, int k) {
  const int f = m.framed.find(k);
  assert(f >= 0 && "frame_pair of a node that has none");
  return m.frame_pair[size_t(f)];
}

[[maybe_unused]] static Vec3 neighbourhood_normal(const ShapeMemory& m, int k,
                                                  std::span<const Vec3> p, const Vec3& g) {
  const auto nb = m.neighbours.row(k);
  return m.surface ? ring_normal(nb, p, g) : pair_normal(nb, frame_pair(m, k), p, g);
}

// The paper's frame: surface nodes from the normal and the first neighbour, interior
// nodes by Gram-Schmidt on the rest-time most orthogonal pair of neighbour directions.
[[maybe_unused]] static Eigen::Matrix3d local_frame(const ShapeMemory& m, int k,
                                                    std::span<const Vec3> p, const Vec3& g) {
  const auto nb = m.neighbours.row(k);
  Eigen::Matrix3d R;
  if (m.surface) {
    const Vec3 n = ring_normal(nb, p, g).normalized();
    Vec3 e1 = p[nb[0]] - g;
    e1 = (e1 - e1.dot(n) * n).normalized();
    R << e1, n.cross(e1), n;
  } else {
    const std::array<int, 2>& pair = frame_pair(m, k);
    const Vec3 e1 = (p[nb[pair[0]]] - g).normalized();
    Vec3 u = p[nb[pair[1]]] - g;
    const Vec3 e2 = (u - u.dot(e1) * e1).normalized();
    R << e1, e2, e1.cross(e2);
  }
  return R;
}

}  // namespace phymul
