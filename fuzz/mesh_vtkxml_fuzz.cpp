// libFuzzer target: the VTK XML readers (.vtu grids, .vtp surfaces and the surface checks
// behind them), in every encoding: base64, appended raw, zlib blocks. Any input is a mesh whose
// cells index its points or a MeshFileError naming the input; any other exception, a crash,
// a hang or a sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "mesh_checks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    // The file's declared type picks the reader, as its extension would.
    fuzz::check_mesh(bytes.find("\"PolyData\"") != std::string::npos
                         ? phymul::parse_vtp_mesh(bytes, "fuzz")
                         : phymul::parse_vtu_mesh(bytes, "fuzz"));
  } catch (const phymul::MeshFileError& e) {
    fuzz::check_error(e);
  }
  return 0;
}
