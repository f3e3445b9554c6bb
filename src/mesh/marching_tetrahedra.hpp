// The zero level set of a sampled function as a closed triangle surface: each grid cube cut
// into six tetrahedra around its main diagonal (the same cut in every cube, so neighbours
// agree), the function linear in each. No value may be exactly zero.
#pragma once

#include <array>
#include <vector>

#include "phymul/mesh.hpp"

namespace phymul::detail {

struct ScalarGrid {
  std::array<int, 3> nodes{0, 0, 0};  // along x, y, z; x fastest
  Vec3 spacing = Vec3::Ones();        // between nodes
  std::vector<float> values;          // < 0 inside, > 0 outside, never 0
};

// Triangles with outward normals (from negative towards positive values), points in the
// grid's frame (node (0, 0, 0) at the origin). Closed and manifold when every value on the
// grid's border is positive.
Mesh marching_tetrahedra(const ScalarGrid& grid);

}  // namespace phymul::detail
