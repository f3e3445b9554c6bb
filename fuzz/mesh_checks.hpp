// What every mesh fuzz target asks of a reader's answer: a mesh whose cells use its points
// only, or a MeshFileError with a message naming the input. Anything else aborts (a finding).
#pragma once

#include <cstdio>
#include <cstdlib>

#include "phymul/mesh_io.hpp"

namespace fuzz {

inline void check_mesh(const phymul::Mesh& mesh) {
  for (const phymul::Cell& c : mesh.cells)
    for (int i : c.node_span())
      if (i < 0 || i >= int(mesh.points.size())) {
        std::fprintf(stderr, "cell node %d outside %zu points\n", i, mesh.points.size());
        std::abort();
      }
}

inline void check_error(const phymul::MeshFileError& e) {
  if (e.message.empty() || e.file != "fuzz") {
    std::fprintf(stderr, "MeshFileError without a message or file\n");
    std::abort();
  }
}

}  // namespace fuzz
