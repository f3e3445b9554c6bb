// Checks a closed triangle surface before it is used as an organ's boundary (a surface read
// from STL, OBJ or PLY): no degenerate triangle, every edge shared by exactly two triangles
// (closed and manifold), one orientation throughout, outward, and no two triangles crossing.
// Orientation is repaired (flipped triangles, a surface turned inside out); the rest is not.
#pragma once

#include <string>
#include <vector>

#include "phymul/mesh.hpp"

namespace phymul {

struct SurfaceCheck {
  std::vector<std::string> problems;  // each a sentence naming the triangles, edges or points
  std::vector<std::string> repairs;   // what was changed, for the user to read
};

// Checks, and repairs the orientation of, the triangles of `mesh` (all its cells must be
// triangles). The first problems found are listed (at most `max_problems`); a surface with
// problems is left as it was given.
SurfaceCheck check_closed_surface(Mesh& mesh, size_t max_problems = 10);

// Merges points with bit-identical coordinates (an STL file repeats each vertex in every
// triangle), renumbering the cells and dropping the unused copies. Returns how many went.
size_t merge_duplicate_points(Mesh& mesh);

}  // namespace phymul
