// libFuzzer target: the CamiTK readers (camitk.hpp). Any input is read as a PML model, each
// exclusive component made an object's mesh, and as LML loads: the answer is meshes whose
// cells index their points and loads with sorted finite events, or a MeshFileError naming the
// input; any other exception, a crash or a sanitizer report is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "mesh_checks.hpp"
#include "phymul/camitk.hpp"

namespace {

void check_loads(const std::vector<phymul::LmlLoad>& loads) {
  for (const phymul::LmlLoad& l : loads)
    for (size_t k = 0; k < l.dates.size(); ++k)
      if (!std::isfinite(l.values[k]) || (k > 0 && !(l.dates[k] > l.dates[k - 1]))) {
        std::fprintf(stderr, "LML events not finite or not sorted\n");
        std::abort();
      }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const phymul::PmlModel pml = phymul::parse_pml(text, "fuzz", 1000.0);
    for (const phymul::PmlComponent& c : pml.components) try {
        if (c.exclusive) fuzz::check_mesh(phymul::pml_object_mesh(pml, c.name, nullptr, "fuzz"));
      } catch (const phymul::MeshFileError& e) {
        fuzz::check_error(e);
      }
  } catch (const phymul::MeshFileError& e) {
    fuzz::check_error(e);
  }
  try {
    check_loads(phymul::parse_lml(text, "fuzz"));
  } catch (const phymul::MeshFileError& e) {
    fuzz::check_error(e);
  }
  return 0;
}
