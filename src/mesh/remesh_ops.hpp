// The local operations of the isotropic remesher (remesh.cpp) on a closed, consistently
// oriented triangle surface. Dead triangles have t[0] == -1; vertices no triangle uses are
// dropped at the end.
#pragma once

#include <vector>

#include "phymul/mesh.hpp"

namespace phymul::remesh {

struct Work {
  std::vector<Vec3> x;
  std::vector<Triangle> t;
};

// Splits edges longer than `high` at their midpoint, until none is.
void split_long(Work& w, double high);
// Collapses edges shorter than `low` into their midpoint where that keeps the surface a
// manifold, flips no triangle and makes no edge longer than `high`.
void collapse_short(Work& w, double low, double high);
// Flips edges where that brings the four vertices' valences closer to 6.
void flip_to_valence(Work& w);
// Drops dead triangles and the vertices no triangle uses (a fine input's collapsed points
// would otherwise be relaxed and projected every round).
void compact(Work& w);
// Moves each vertex in its tangent plane towards the area-weighted centre of its triangles.
void relax(Work& w);

}  // namespace phymul::remesh
