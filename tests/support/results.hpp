// Comparing two runs' output directories: the same files, byte for byte, and the same
// report.json but for what no rerun reproduces.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <sstream>
#include <string>

#include "support/process.hpp"

namespace phymul::testing {

// report.json without the wall-clock figures and the message (it names the output directory).
inline std::string report_numbers(const std::filesystem::path& dir) {
  std::istringstream in(read_text(dir / "report.json"));
  std::string line, kept;
  while (std::getline(in, line))
    if (line.find("wall_time") == std::string::npos &&
        line.find("ns_per_node_per_step") == std::string::npos &&
        line.find("real_time_factor") == std::string::npos &&
        line.find("\"message\"") == std::string::npos)
      kept += line + '\n';
  return kept;
}

inline void expect_same_results(const std::filesystem::path& reference,
                                const std::filesystem::path& resumed) {
  namespace fs = std::filesystem;
  std::set<std::string> a, b;
  for (const auto& e : fs::directory_iterator(reference)) a.insert(e.path().filename());
  for (const auto& e : fs::directory_iterator(resumed)) b.insert(e.path().filename());
  EXPECT_EQ(a, b);
  ASSERT_GE(a.size(), 3u);  // frames, monitors.csv, report.json at least
  for (const std::string& name : a) {
    if (name == "report.json") continue;
    EXPECT_TRUE(read_text(reference / name) == read_text(resumed / name)) << name << " differs";
  }
  EXPECT_EQ(report_numbers(reference), report_numbers(resumed));
}

}  // namespace phymul::testing
