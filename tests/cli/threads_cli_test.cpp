// `phymul run --threads N`: the count is used and reported, and the results are the same
// bytes whatever it is.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "support/process.hpp"

namespace phymul {
namespace {

namespace fs = std::filesystem;
using testing::read_text;
using testing::TempDir;

// 17^3 = 4913 nodes: above the size from which loops and force passes go parallel.
constexpr const char* kScene = R"(simulation:
  dt: auto
  duration: 0.02 s
  gravity: [0, 0, -9.81 m/s^2]
  damping: 5 1/s
objects:
  - name: cube
    mesh: {generator: box, element: hexa, size: [4 cm, 4 cm, 4 cm], cells: [16, 16, 16]}
    material: {stiffness: 200 N/m, density: 1000 kg/m^3}
    volume_constraint: true
constraints:
  - {type: fixed, object: cube, nodes: top}
output:
  interval: 0.01 s
)";

TEST(CliThreads, OneAndTwoThreadsWriteTheSameBytesAndSaySo) {
  TempDir dir;
  const fs::path scene = dir.path() / "cube.yaml";
  std::ofstream(scene) << kScene;
  for (int threads : {1, 2}) {
    const fs::path out = dir.path() / (threads == 1 ? "t1" : "t2");
    const auto r = testing::run_command(testing::cli() + " run " + scene.string() + " -o " +
                                        out.string() + " -q --threads " + std::to_string(threads));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(read_text(out / "report.json").find("\"threads\": " + std::to_string(threads)),
              std::string::npos);
  }
  int compared = 0;
  for (const auto& e : fs::directory_iterator(dir.path() / "t1")) {
    const std::string name = e.path().filename();
    if (name == "report.json") continue;
    // Where they part, not gtest's diff of two large texts (which takes minutes).
    const std::string one = read_text(e.path()), two = read_text(dir.path() / "t2" / name);
    const auto apart = std::mismatch(one.begin(), one.end(), two.begin(), two.end());
    EXPECT_TRUE(one == two) << name << " differs from byte " << (apart.first - one.begin())
                            << " (sizes " << one.size() << " and " << two.size() << ")";
    ++compared;
  }
  EXPECT_GE(compared, 4);  // frames, the .pvd and monitors.csv
}

TEST(CliThreads, ZeroThreadsIsRefused) {
  const auto r = testing::run_command(testing::cli() + " run nothing.yaml --threads 0");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--threads"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace phymul
