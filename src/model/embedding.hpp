// Points embedded in volume cells by barycentric weights (no remeshing): a needle's track
// points and target (Needle) ride with the tissue they were found in.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "phymul/model.hpp"

namespace phymul {

// The component's volume cells as tetrahedra, global ids: a tetrahedron as it is, a
// hexahedron in six around its 0-6 diagonal, a wedge in three. Empty for a surface.
std::vector<std::array<int, 4>> cell_tetrahedra(const Model& model, int component);

// Barycentric weights of p in the tetrahedron at x (they sum to one; all >= 0 inside);
// false when it is degenerate.
bool barycentric(const std::array<int, 4>& tet, std::span<const Vec3> x, const Vec3& p,
                 std::array<double, 4>& weights);

// The first tetrahedron holding p (weights >= -tolerance) at positions x; false when none.
bool embed_point(std::span<const std::array<int, 4>> tetrahedra, std::span<const Vec3> x,
                 const Vec3& p, EmbeddedPoint& out, double tolerance = 1e-9);

}  // namespace phymul
