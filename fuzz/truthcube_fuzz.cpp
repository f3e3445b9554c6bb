// libFuzzer target: the Truth Cube bead CSV reader. Malformed input must end in a
// std::runtime_error naming the problem; a crash or any other exception is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "phymul/studies/truthcube.hpp"

namespace {

// The file load_beads reads, one per fuzzing process, removed when the process exits.
struct ScratchFile {
  std::filesystem::path path = std::filesystem::temp_directory_path() /
                               ("phymul_truthcube_fuzz_" + std::to_string(::getpid()) + ".csv");
  ~ScratchFile() {
    std::error_code ec;
    std::filesystem::remove(path, ec);
  }
};

const std::filesystem::path& scratch_file() {
  static const ScratchFile file;
  return file.path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto& path = scratch_file();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    if (!out) {
      std::fprintf(stderr, "cannot write %s\n", path.c_str());
      std::abort();
    }
  }
  try {
    phymul::truthcube::load_beads(path);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
