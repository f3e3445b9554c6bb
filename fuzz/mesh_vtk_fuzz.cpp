// libFuzzer target: the vtk mesh reader. Any input is either a mesh whose cells index its
// points, or a MeshFileError naming a place in the file; any other exception, a crash or a
// sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "mesh_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    fuzz::check_mesh(phymul::parse_vtk_mesh(text, "fuzz"));
  } catch (const phymul::MeshFileError& e) {
    fuzz::check_error(e);
  }
  return 0;
}
