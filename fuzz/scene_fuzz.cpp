// libFuzzer target: the scene reader (parsing and the schema's checks; no file is read). Any input
// is either a Scene or a SceneError with at least one diagnostic; any other exception, a crash or a
// sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "io/scene_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    phymul::read_scene_text(text, "fuzz.yaml");
  } catch (const phymul::SceneError& e) {
    if (e.diagnostics().empty()) {
      std::fprintf(stderr, "SceneError without diagnostics\n");
      std::abort();
    }
  }
  // Anything else propagates: libFuzzer reports an uncaught exception as a crash.
  return 0;
}
