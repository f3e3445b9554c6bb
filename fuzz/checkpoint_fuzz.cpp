// libFuzzer target: the checkpoint reader. Any input is either a checkpoint whose arrays agree
// in size, or a CheckpointError; any other exception, a crash or a sanitizer report is a
// finding. (The checksum stops most mutations early: the corpus seeds include files whose
// checksum the target recomputes, so that the field checks behind it are fuzzed too.)
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "phymul/checkpoint.hpp"

namespace {

void parse(const std::string& bytes) {
  try {
    const phymul::Checkpoint c = phymul::parse_checkpoint(bytes, "fuzz");
    if (c.data.v.size() != c.data.x.size() || c.data.f.size() != c.data.x.size()) {
      std::fprintf(stderr, "arrays of different sizes accepted\n");
      std::abort();
    }
  } catch (const phymul::CheckpointError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string bytes(reinterpret_cast<const char*>(data), size);
  parse(bytes);
  // The same bytes with the header's size and the checksum made right.
  constexpr size_t kHeader = 32;
  if (bytes.size() >= kHeader + 8) {
    const uint64_t body = bytes.size() - kHeader - 8;
    std::memcpy(bytes.data() + 24, &body, 8);
    const uint64_t sum = phymul::fnv1a(std::string_view(bytes).substr(kHeader, body));
    std::memcpy(bytes.data() + kHeader + body, &sum, 8);
    parse(bytes);
  }
  return 0;
}
