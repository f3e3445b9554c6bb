// ResultWriter's series: the .pvd files may lag the frames while a run goes on (each rewrite
// creates a file), but once the writer is finished, or destroyed by an error, both series
// list every frame written, at its time, and every file they list is there.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <charconv>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "phymul/results.hpp"
#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

namespace fs = std::filesystem;

constexpr const char* kScene = R"(simulation: {dt: 1 ms, duration: 1 s, gravity: [0, 0, -9.81]}
objects:
  - name: jelly
    mesh: {generator: box, size: [2 cm, 2 cm, 2 cm], cells: [2, 2, 2]}
    material: {stiffness: 5 N/m, density: 1000 kg/m^3}
obstacles:
  - {name: floor, shape: plane, position: [0, 0, -1.5 cm], axis: [0, 0, 1]}
)";

struct Listed {
  std::string time, file;
};

std::vector<Listed> series(const fs::path& pvd) {
  const std::string text = testing::read_text(pvd);
  const std::regex entry(R"re(timestep="([^"]*)" group="" part="0" file="([^"]*)")re");
  std::vector<Listed> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), entry);
       it != std::sregex_iterator(); ++it)
    out.push_back({(*it)[1], (*it)[2]});
  return out;
}

double parse(const std::string& text) {
  double value = -1.0;
  std::from_chars(text.data(), text.data() + text.size(), value);
  return value;
}

// Writes `frames` frames a step apart; returns their times (s).
std::vector<double> write_frames(ResultWriter& writer, Simulator& sim, int frames) {
  std::vector<double> times;
  for (int k = 0; k < frames; ++k) {
    sim.step();
    writer.frame(sim);
    times.push_back(sim.data().time);
  }
  return times;
}

void expect_complete(const fs::path& dir, const std::vector<double>& times) {
  const std::vector<Listed> body = series(dir / "jelly.pvd");
  const std::vector<Listed> floor = series(dir / "jelly_obstacles.pvd");
  ASSERT_EQ(body.size(), times.size());
  ASSERT_EQ(floor.size(), times.size());
  for (size_t k = 0; k < times.size(); ++k) {
    EXPECT_EQ(parse(body[k].time), times[k]);  // bit for bit: shortest round-trip text
    EXPECT_EQ(parse(floor[k].time), times[k]);
    EXPECT_EQ(body[k].file, fmt::format("jelly_{:06d}.vtu", k));
    EXPECT_EQ(floor[k].file, fmt::format("jelly_obstacles_{:06d}.vtu", k));
    EXPECT_TRUE(fs::is_regular_file(dir / body[k].file));
    EXPECT_TRUE(fs::is_regular_file(dir / floor[k].file));
  }
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().filename() != "monitors.csv.tmp") {  // finish() completes monitors.csv
      EXPECT_NE(e.path().extension(), ".tmp") << "left behind: " << e.path();
    }
  }
}

TEST(ResultWriter, FinishedSeriesListEveryFrame) {
  testing::TempDir dir;
  Simulator sim(compile_scene(parse_scene(kScene, "jelly.yaml")));
  ResultWriter writer(dir.path(), "jelly", sim.model(), true, VtuEncoding::binary);
  const std::vector<double> times = write_frames(writer, sim, 7);
  // The first frame is listed at once, whatever the clock says.
  ASSERT_GE(series(dir.path() / "jelly.pvd").size(), 1u);
  RunReport report;
  writer.finish(report);
  expect_complete(dir.path(), times);
}

TEST(ResultWriter, SeriesOfAWriterDestroyedUnfinishedListEveryFrame) {
  testing::TempDir dir;
  Simulator sim(compile_scene(parse_scene(kScene, "jelly.yaml")));
  std::vector<double> times;
  {
    ResultWriter writer(dir.path(), "jelly", sim.model(), true, VtuEncoding::ascii);
    times = write_frames(writer, sim, 5);
  }
  expect_complete(dir.path(), times);
}

}  // namespace
}  // namespace phymul
