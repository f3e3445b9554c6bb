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

TEST(Cli, SceneReferenceDocIsTheGeneratedOne) {
  const auto r = run_command(cli() + " schema");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string doc = testing::read_text(source_dir() / "docs/scene-reference.md");
  const std::string begin = "<!-- scene-reference:begin -->\n",
                    end = "<!-- scene-reference:end -->";
  const size_t b = doc.find(begin), e = doc.find(end);
  ASSERT_NE(b, std::string::npos);
  ASSERT_NE(e, std::string::npos);
  EXPECT_EQ(doc.substr(b + begin.size(), e - b - begin.size()), r.output)
      << "regenerate docs/scene-reference.md with: build/phymul schema";
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
          << e.path() << " lacks: " << line.substr(10) << "\ngot:\n"
          << r.output;
    }
    EXPECT_GT(expectations, 0) << e.path();
  }
  EXPECT_GE(seen, 4);
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// A time step ten times the stability limit: the run stops with exit code 3, a report that
// says why, and only finite frames behind it.
TEST(Cli, UnstableRunStopsWithAdviceAndAValidSeries) {
  testing::TempDir dir;
  const auto scene = dir.path() / "shaky.yaml";
  std::ofstream(scene) << R"(simulation:
  dt: 0.05 s
  duration: 5 s
  gravity: [0, 0, -9.81]
objects:
  - name: jelly
    mesh: {generator: box, size: [2 cm, 2 cm, 2 cm], cells: [2, 2, 2]}
    material: {stiffness: 50 N/m, density: 1000 kg/m^3}
constraints:
  - {type: fixed, object: jelly, nodes: top}
output:
  interval: 0.05 s
)";
  const auto out = dir.path() / "out";
  const auto r = testing::run_command(testing::cli() + " run " + scene.string() + " -o " +
                                      out.string() + " -q");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("component 'jelly'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("set simulation.dt smaller"), std::string::npos) << r.output;
  const std::string report = testing::read_text(out / "report.json");
  EXPECT_NE(report.find("\"status\": \"unstable\""), std::string::npos) << report;
  for (const auto& e : std::filesystem::directory_iterator(out)) {
    EXPECT_NE(e.path().extension(), ".tmp") << e.path();
    if (e.path().extension() == ".vtu") {
      EXPECT_EQ(testing::read_text(e.path()).find("nan"), std::string::npos) << e.path();
    }
  }
}

}  // namespace
}  // namespace phymul
