// A bad-input corpus's expected messages: expected.txt holds "file | message" lines ('#'
// starts a comment).
#pragma once

#include <gtest/gtest.h>

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

// Every file of the corpus `dir` but expected.txt is refused by read (which throws E) with its
// expected message, the message starting with the file's path; there are at least `at_least`.
template <class E, class Read>
void expect_every_file_refused(const std::filesystem::path& dir, Read read, int at_least) {
  const std::map<std::string, std::string> expected = expected_messages(dir / "expected.txt");
  int seen = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name == "expected.txt") continue;
    ++seen;
    ASSERT_TRUE(expected.contains(name)) << name << " has no line in expected.txt";
    try {
      read(e.path());
      ADD_FAILURE() << name << " was read without complaint";
    } catch (const E& error) {
      const std::string what = error.what();
      EXPECT_NE(what.find(expected.at(name)), std::string::npos)
          << name << "\n  expected: " << expected.at(name) << "\n  got:      " << what;
      EXPECT_TRUE(what.starts_with(e.path().string())) << what;
    }
  }
  EXPECT_EQ(seen, int(expected.size()));
  EXPECT_GE(seen, at_least);
}

}  // namespace phymul::testing
