// libFuzzer target: the closed-surface readers (STL ASCII and binary, OBJ, PLY ASCII and
// binary) and the surface checks behind them, the reader chosen by the content as a file's
// extension would. Any input is a checked closed surface or a MeshFileError with a message;
// any other exception, a crash or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "mesh_checks.hpp"

namespace {

phymul::Mesh parse(const std::string& bytes) {
  if (bytes.starts_with("ply")) return phymul::parse_ply_mesh(bytes, "fuzz");
  if (bytes.starts_with("solid") || bytes.size() >= 84)
    return phymul::parse_stl_mesh(bytes, "fuzz");
  return phymul::parse_obj_mesh(bytes, "fuzz");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    const phymul::Mesh mesh = parse(bytes);
    fuzz::check_mesh(mesh);
    for (const phymul::Cell& c : mesh.cells)
      if (c.type != phymul::CellType::triangle) {
        std::fprintf(stderr, "a surface reader returned a %s\n", phymul::cell_type_name(c.type));
        std::abort();
      }
  } catch (const phymul::MeshFileError& e) {
    fuzz::check_error(e);
  }
  return 0;
}
