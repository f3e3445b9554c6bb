#include <gtest/gtest.h>

#include "support/process.hpp"

namespace phymul {
namespace {

using testing::cli;
using testing::run_command;
using testing::source_dir;

TEST(Cli, EveryExampleChecksClean) {
  int seen = 0;
  for (const auto& e : std::filesystem::directory_iterator(source_dir() / "examples")) {
    if (e.path().extension() != ".yaml") continue;
    ++seen;
    const auto r = run_command(cli() + " check " + e.path().string());
    EXPECT_EQ(r.exit_code, 0) << e.path() << '\n' << r.output;
    EXPECT_NE(r.output.find(": ok ("), std::string::npos) << r.output;
  }
  EXPECT_GE(seen, 3);
}

TEST(Cli, BadScenesExitNonZeroWithLocatedMessages) {
  int seen = 0;
  for (const auto& e :
       std::filesystem::directory_iterator(source_dir() / "tests/data/bad_scenes")) {
    if (e.path().extension() != ".yaml") continue;
    ++seen;
    const auto r = run_command(cli() + " check " + e.path().string());
    EXPECT_EQ(r.exit_code, 1) << e.path() << '\n' << r.output;
    // Every report starts with the file name and a position.
    EXPECT_NE(r.output.find(e.path().filename().string()), std::string::npos) << r.output;
  }
  EXPECT_GE(seen, 20);
}

TEST(Cli, MissingSceneFileIsAnError) {
  const auto r = run_command(cli() + " check /nonexistent/scene.yaml");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("/nonexistent/scene.yaml"), std::string::npos) << r.output;
}

TEST(Cli, ReadmeSceneReferenceIsTheGeneratedOne) {
  const auto r = run_command(cli() + " schema");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string readme = testing::read_text(source_dir() / "README.md");
  const std::string begin = "<!-- scene-reference:begin -->\n",
                    end = "<!-- scene-reference:end -->";
  const size_t b = readme.find(begin), e = readme.find(end);
  ASSERT_NE(b, std::string::npos);
  ASSERT_NE(e, std::string::npos);
  EXPECT_EQ(readme.substr(b + begin.size(), e - b - begin.size()), r.output)
      << "regenerate the README section with: build/phymul schema";
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// Scenes that parse but describe an impossible model: each file's `# expect:` lines must
// appear in `phymul check`'s report, with a non-zero exit.
TEST(Cli, BadModelsAreReportedAtTheirLocation) {
  int seen = 0;
  for (const auto& e :
       std::filesystem::directory_iterator(testing::source_dir() / "tests/data/bad_models")) {
    if (e.path().extension() != ".yaml") continue;
    ++seen;
    const auto r = testing::run_command(testing::cli() + " check " + e.path().string());
    EXPECT_EQ(r.exit_code, 1) << e.path() << '\n' << r.output;
    std::istringstream lines(testing::read_text(e.path()));
    int expectations = 0;
    for (std::string line; std::getline(lines, line);) {
      if (!line.starts_with("# expect: ")) continue;
      ++expectations;
      EXPECT_NE(r.output.find(line.substr(10)), std::string::npos)
          << e.path() << " lacks: " << line.substr(10) << "\ngot:\n" << r.output;
    }
    EXPECT_GT(expectations, 0) << e.path();
  }
  EXPECT_GE(seen, 4);
}

}  // namespace
}  // namespace phymul
