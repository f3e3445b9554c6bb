// Wedges into tetrahedra that conform across shared faces: every quadrilateral face is cut
// along the diagonal through its smallest node index (Dompierre et al. 1999, "How to
// subdivide pyramids, prisms and hexahedra into tetrahedra"), which any prism admits.
#include <algorithm>

#include "phymul/mesh.hpp"

namespace phymul {

std::array<Cell, 3> wedge_tetrahedra(const Cell& wedge) {
  const auto& n = wedge.nodes;
  // Relabel so that v[0] holds the smallest index: rotate the triangles, swapping them when
  // it lies on the second one (orientation is the caller's to fix).
  const int m = int(std::min_element(n.begin(), n.begin() + 6) - n.begin());
  const int r = m % 3, top = m < 3 ? 0 : 3, bottom = 3 - top;
  const std::array<int, 6> v{n[top + r],    n[top + (r + 1) % 3],    n[top + (r + 2) % 3],
                             n[bottom + r], n[bottom + (r + 1) % 3], n[bottom + (r + 2) % 3]};
  // The faces through v[0] are cut from v[0]; the opposite face v1 v2 v5 v4 from its smallest.
  const std::array<std::array<int, 4>, 3> t =
      std::min(v[1], v[5]) < std::min(v[2], v[4])
          ? std::array<std::array<int, 4>, 3>{{{v[0], v[1], v[2], v[5]},
                                               {v[0], v[1], v[5], v[4]},
                                               {v[0], v[4], v[5], v[3]}}}
          : std::array<std::array<int, 4>, 3>{
                {{v[0], v[1], v[2], v[4]}, {v[0], v[4], v[2], v[5]}, {v[0], v[4], v[5], v[3]}}};
  std::array<Cell, 3> cells;
  for (int k = 0; k < 3; ++k) {
    cells[k].type = CellType::tetra;
    std::copy(t[k].begin(), t[k].end(), cells[k].nodes.begin());
  }
  return cells;
}

}  // namespace phymul
