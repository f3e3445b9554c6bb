// libFuzzer target: the vtk mesh reader. Any input is either a mesh whose cells index its
// points, or a MeshFileError naming a place in the file; any other exception, a crash or a
// sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "phymul/mesh_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const phymul::Mesh mesh = phymul::parse_vtk_mesh(text, "fuzz");
    for (const phymul::Cell& c : mesh.cells)
      for (int i : c.node_span())
        if (i < 0 || i >= int(mesh.points.size())) {
          std::fprintf(stderr, "cell node %d outside %zu points\n", i, mesh.points.size());
          std::abort();
        }
  } catch (const phymul::MeshFileError& e) {
    if (e.message.empty() || e.file != "fuzz") {
      std::fprintf(stderr, "MeshFileError without a message or file\n");
      std::abort();
    }
  }
  return 0;
}
