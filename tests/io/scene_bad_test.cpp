// Bad scenes: every problem is reported, with its position, and nothing but SceneError
// ever escapes the reader.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

namespace fs = std::filesystem;

fs::path bad_scenes() { return testing::source_dir() / "tests/data/bad_scenes"; }

// "# expect: <substring>" lines of a corpus file: each names one diagnostic.
std::vector<std::string> expectations(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> out;
  const std::string tag = "# expect: ";
  for (std::string line; std::getline(in, line);)
    if (line.rfind(tag, 0) == 0) out.push_back(line.substr(tag.size()));
  return out;
}

std::vector<fs::path> corpus() {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(bad_scenes()))
    if (entry.path().extension() == ".yaml") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

// The SceneError raised by `load`, or a test failure.
template <class Load>
std::vector<Diagnostic> diagnostics_of(Load load) {
  try {
    load();
  } catch (const SceneError& e) {
    return e.diagnostics();
  }
  ADD_FAILURE() << "no SceneError";
  return {};
}

std::string joined(const std::vector<Diagnostic>& diagnostics) {
  std::string out;
  for (const auto& d : diagnostics) out += d.str() + "\n";
  return out;
}

TEST(SceneBadTest, CorpusHasAtLeastTwentyFilesEachWithExpectations) {
  const auto files = corpus();
  EXPECT_GE(files.size(), 20u);
  for (const auto& file : files) EXPECT_FALSE(expectations(file).empty()) << file;
}

TEST(SceneBadTest, EveryCorpusFileReportsExactlyItsExpectedDiagnostics) {
  for (const auto& file : corpus()) {
    SCOPED_TRACE(file.filename().string());
    const auto expected = expectations(file);
    const auto diagnostics = diagnostics_of([&] { load_scene(file); });
    const std::string report = joined(diagnostics);
    for (const auto& text : expected)
      EXPECT_NE(report.find(text), std::string::npos) << "missing: " << text << "\nin:\n" << report;
    // One expectation per diagnostic: no cascade of follow-up messages goes unnoticed.
    EXPECT_EQ(diagnostics.size(), expected.size()) << report;
  }
}

TEST(SceneBadTest, WhatJoinsAllDiagnosticsWithNewlines) {
  try {
    load_scene(bad_scenes() / "out_of_range.yaml");
    FAIL() << "no SceneError";
  } catch (const SceneError& e) {
    std::string lines;
    for (const auto& d : e.diagnostics()) lines += (lines.empty() ? "" : "\n") + d.str();
    EXPECT_EQ(e.what(), lines);
    EXPECT_GT(e.diagnostics().size(), 1u);
  }
}

TEST(SceneBadTest, DiagnosticsAreSortedByPosition) {
  const auto diagnostics = diagnostics_of([] { load_scene(bad_scenes() / "out_of_range.yaml"); });
  EXPECT_TRUE(std::is_sorted(diagnostics.begin(), diagnostics.end(), [](auto& a, auto& b) {
    return std::pair(a.loc.line, a.loc.column) < std::pair(b.loc.line, b.loc.column);
  }));
}

TEST(SceneBadTest, MissingFileNamesTheFileAndTheReason) {
  const auto diagnostics = diagnostics_of([] { load_scene("/nonexistent/scene.yaml"); });
  ASSERT_EQ(diagnostics.size(), 1u);
  EXPECT_EQ(diagnostics[0].str(),
            "cannot read scene file '/nonexistent/scene.yaml': No such file or directory");
}

TEST(SceneBadTest, DirectoryIsNotAScene) {
  const auto diagnostics = diagnostics_of([] { load_scene(bad_scenes()); });
  ASSERT_EQ(diagnostics.size(), 1u);
  EXPECT_NE(diagnostics[0].str().find("Is a directory"), std::string::npos);
}

fs::path temp_file(const std::string& name, const std::string& bytes) {
  const fs::path path = fs::temp_directory_path() / name;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

TEST(SceneBadTest, BinaryGarbageIsReportedNotCrashed) {
  std::mt19937 random(1234);
  for (int round = 0; round < 20; ++round) {
    std::string bytes(4096, '\0');
    for (char& c : bytes) c = char(random() & 0xFF);
    const fs::path path = temp_file("phymul_scene_garbage.yaml", bytes);
    const auto diagnostics = diagnostics_of([&] { load_scene(path); });
    ASSERT_EQ(diagnostics.size(), 1u);
    EXPECT_NE(diagnostics[0].message.find("is it a binary file?"), std::string::npos)
        << diagnostics[0].str();
    fs::remove(path);
  }
}

TEST(SceneBadTest, NulByteIsReportedWithItsPosition) {
  const std::string text = std::string("objects:\n  - name: a") + '\0' + "b\n";
  const auto diagnostics = diagnostics_of([&] { parse_scene(text, "nul.yaml"); });
  ASSERT_EQ(diagnostics.size(), 1u);
  EXPECT_EQ(diagnostics[0].str(),
            "nul.yaml:2:12: scene file is not YAML text (byte 0x00 is a control character); is it "
            "a binary file?");
}

TEST(SceneBadTest, InvalidUtf8IsReported) {
  const auto diagnostics = diagnostics_of([] { parse_scene("a: \xC3\x28\n", "latin.yaml"); });
  ASSERT_EQ(diagnostics.size(), 1u);
  EXPECT_EQ(diagnostics[0].str(),
            "latin.yaml:1:4: scene file is not YAML text (byte 0xc3 is not valid UTF-8); is it a "
            "binary file?");
}

TEST(SceneBadTest, DeepNestingIsRefusedWithoutStackOverflow) {
  const auto diagnostics =
      diagnostics_of([] { parse_scene("objects: " + std::string(100000, '['), "deep.yaml"); });
  ASSERT_EQ(diagnostics.size(), 1u);
  EXPECT_NE(diagnostics[0].message.find("YAML nesting is too deep"), std::string::npos);
}

TEST(SceneBadTest, EmptyAndBlankTextsAreEmptyScenes) {
  for (const std::string text : {"", "\n\n", "   # just a comment\n", "---\n"}) {
    const auto diagnostics = diagnostics_of([&] { parse_scene(text, "e.yaml"); });
    ASSERT_EQ(diagnostics.size(), 1u);
    EXPECT_NE(diagnostics[0].str().find("e.yaml: scene file is empty"), std::string::npos)
        << diagnostics[0].str();
  }
}

const std::string kValidScene = R"(simulation:
  dt: 0.1 ms
  duration: 2 s
  gravity: [0, 0, -9.81 m/s^2]
objects:
  - name: cube
    mesh: {generator: box, size: [40 mm, 40 mm, 40 mm], cells: [8, 8, 8]}
    material: {stiffness: 50 N/m, density: 1000 kg/m^3, frame: polar}
loads:
  - type: force
    object: cube
    nodes: {sphere: {center: [0, 0, 2 cm], radius: 5 mm}}
    schedule:
      - {t: 0 s, value: [0, 0, 0]}
      - {t: 1 s, value: [0, 0, -0.1 N]}
constraints:
  - type: displacement
    object: cube
    nodes: "0-3,7"
    axes: xz
    displacement: [0, 0, -5 mm]
output:
  interval: 0.05 s
)";

// Only SceneError may leave the reader, whatever the input.
void expect_scene_or_scene_error(const std::string& text) {
  try {
    parse_scene(text, "fuzz.yaml");
  } catch (const SceneError& e) {
    EXPECT_FALSE(e.diagnostics().empty());
  } catch (const std::exception& e) {
    ADD_FAILURE() << "unexpected " << e.what() << " for:\n" << text;
  }
}

TEST(SceneBadTest, EveryPrefixOfAValidSceneIsASceneOrASceneError) {
  ASSERT_NO_THROW(parse_scene(kValidScene, "valid.yaml"));
  for (size_t length = 0; length <= kValidScene.size(); ++length)
    expect_scene_or_scene_error(kValidScene.substr(0, length));
}

TEST(SceneBadTest, RandomEditsOfAValidSceneAreASceneOrASceneError) {
  std::mt19937 random(42);
  const std::string alphabet = " \n-:[]{},#&*!|>'\"0123456789.eE+abcxyz\t%@`";
  for (int round = 0; round < 3000; ++round) {
    std::string text = kValidScene;
    for (int edit = 0; edit < 3; ++edit) {
      const size_t at = random() % text.size();
      const char c = alphabet[random() % alphabet.size()];
      if (random() % 2 == 0)
        text[at] = c;
      else
        text.insert(text.begin() + long(at), c);
    }
    expect_scene_or_scene_error(text);
  }
}

}  // namespace
}  // namespace phymul
