// A bad-input corpus's expected messages: expected.txt holds "file | message" lines ('#'
// starts a comment).
#pragma once

#include <filesystem>
#include <map>
#include <sstream>
#include <string>

#include "support/process.hpp"

namespace phymul::testing {

inline std::map<std::string, std::string> expected_messages(const std::filesystem::path& file) {
  std::map<std::string, std::string> expected;
  std::istringstream lines(read_text(file));
  for (std::string line; std::getline(lines, line);) {
    const auto bar = line.find(" | ");
    if (line.empty() || line[0] == '#' || bar == std::string::npos) continue;
    expected[line.substr(0, bar)] = line.substr(bar + 3);
  }
  return expected;
}

}  // namespace phymul::testing
