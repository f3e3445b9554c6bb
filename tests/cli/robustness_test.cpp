// `phymul run` under stress: interrupted by a signal, run twice, given bad arguments.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "support/process.hpp"

namespace phymul {
namespace {

namespace fs = std::filesystem;
using testing::cli;
using testing::read_text;
using testing::run_command;
using testing::TempDir;

// Long enough (thousands of seconds of simulated time) that only a signal ends it. (At 5 N/m
// this jelly tangled within a second, nodes jumping several cm a step: the runaway guard
// stops that; 50 N/m keeps every step below 2% of an edge.)
constexpr const char* kLongDynamicScene = R"(simulation:
  dt: auto
  duration: 5000 s
  gravity: [0, 0, -9.81]
  damping: 5 1/s
objects:
  - name: jelly
    mesh: {generator: box, size: [2 cm, 2 cm, 2 cm], cells: [6, 6, 6]}
    material: {stiffness: 50 N/m, density: 1000 kg/m^3}
    volume_constraint: true
constraints:
  - {type: fixed, object: jelly, nodes: top}
output:
  interval: 0.05 s
)";

// A static relaxation that cannot reach its tolerance before a signal arrives.
constexpr const char* kLongStaticScene = R"(simulation:
  mode: static
  max_iterations: 100000000
  tolerance: 1e-30 N
  load_steps: 4
  gravity: [0, 0, -9.81]
objects:
  - name: jelly
    mesh: {generator: box, size: [2 cm, 2 cm, 2 cm], cells: [6, 6, 6]}
    material: {stiffness: 5 N/m, density: 1000 kg/m^3}
constraints:
  - {type: fixed, object: jelly, nodes: top}
)";

// Checks the .pvd and every .vtu it lists parse as XML, and that the listed files exist;
// prints "frames N".
constexpr const char* kSeriesChecker = R"(import sys, os, xml.etree.ElementTree as ET
d, stem = sys.argv[1], sys.argv[2]
root = ET.parse(os.path.join(d, stem + '.pvd')).getroot()
sets = root.find('Collection').findall('DataSet')
for s in sets:
    f = os.path.join(d, s.get('file'))
    assert os.path.isfile(f), 'missing ' + f
    ET.parse(f)
print('frames', len(sets))
)";

struct Interrupted {
  int exit_code = -1;
  std::string output;
};

// Starts `phymul run scene -o out`, sends `sig` after `delay`, waits for it to end.
Interrupted run_and_signal(const fs::path& scene, const fs::path& out, const fs::path& log, int sig,
                           std::chrono::milliseconds delay) {
  const std::string exe = cli(), scene_s = scene.string(), out_s = out.string();
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, STDOUT_FILENO);
      dup2(fd, STDERR_FILENO);
    }
    execl(exe.c_str(), exe.c_str(), "run", scene_s.c_str(), "-o", out_s.c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  Interrupted r;
  if (pid < 0) return r;
  std::this_thread::sleep_for(delay);
  kill(pid, sig);
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      r.output = "did not end within 30 s of the signal\n";
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  r.output += read_text(log);
  return r;
}

void expect_interrupted_results(const fs::path& dir, const fs::path& out, int min_frames) {
  const std::string report = read_text(out / "report.json");
  EXPECT_NE(report.find("\"status\": \"interrupted\""), std::string::npos) << report;
  EXPECT_TRUE(fs::is_regular_file(out / "monitors.csv"));
  EXPECT_GT(read_text(out / "monitors.csv").size(), 0u);
  for (const auto& e : fs::directory_iterator(out))
    EXPECT_NE(e.path().extension(), ".tmp") << "left behind: " << e.path();
  const auto script = dir / "series.py";
  std::ofstream(script) << kSeriesChecker;
  const auto check =
      run_command("/usr/bin/python3 " + script.string() + " " + out.string() + " long");
  ASSERT_EQ(check.exit_code, 0) << check.output;
  std::istringstream in(check.output);
  std::string key;
  int frames = 0;
  in >> key >> frames;
  EXPECT_GE(frames, min_frames) << check.output;
}

TEST(Robustness, SigintEndsADynamicRunWithValidResultsAndExitCode130) {
  TempDir dir;
  const auto scene = dir.path() / "long.yaml";
  std::ofstream(scene) << kLongDynamicScene;
  const auto out = dir.path() / "out";
  const auto r =
      run_and_signal(scene, out, dir.path() / "log.txt", SIGINT, std::chrono::milliseconds(1000));
  ASSERT_EQ(r.exit_code, 130) << r.output;
  EXPECT_NE(r.output.find("interrupted"), std::string::npos) << r.output;
  expect_interrupted_results(dir.path(), out, 2);  // t = 0 and the final frame at least
}

TEST(Robustness, SigtermEndsAStaticRelaxationWithValidResultsAndExitCode130) {
  TempDir dir;
  const auto scene = dir.path() / "long.yaml";
  std::ofstream(scene) << kLongStaticScene;
  const auto out = dir.path() / "out";
  const auto r =
      run_and_signal(scene, out, dir.path() / "log.txt", SIGTERM, std::chrono::milliseconds(1000));
  ASSERT_EQ(r.exit_code, 130) << r.output;
  expect_interrupted_results(dir.path(), out, 2);  // the rest state and the final frame
}

constexpr const char* kShortScene = R"(simulation:
  dt: auto
  duration: 0.2 s
  gravity: [0, 0, -9.81]
  damping: 5 1/s
objects:
  - name: jelly
    mesh: {generator: box, size: [2 cm, 2 cm, 2 cm], cells: [4, 4, 4]}
    material: {stiffness: 50 N/m, density: 1000 kg/m^3}
    volume_constraint: true
loads:
  - type: force
    object: jelly
    nodes: bottom
    schedule:
      - {t: 0 s, value: [0, 0, 0]}
      - {t: 0.1 s, value: [0.001 N, 0, -0.002 N]}
constraints:
  - {type: fixed, object: jelly, nodes: top}
output:
  interval: 0.05 s
)";

TEST(Robustness, TwoRunsOfASceneWriteIdenticalFiles) {
  TempDir dir;
  const auto scene = dir.path() / "jelly.yaml";
  std::ofstream(scene) << kShortScene;
  for (const char* name : {"a", "b"}) {
    const auto r =
        run_command(cli() + " run -q " + scene.string() + " -o " + (dir.path() / name).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  int compared = 0;
  for (const auto& e : fs::directory_iterator(dir.path() / "a")) {
    if (e.path().extension() != ".vtu" && e.path().filename() != "monitors.csv") continue;
    const auto other = dir.path() / "b" / e.path().filename();
    ASSERT_TRUE(fs::exists(other)) << other;
    EXPECT_TRUE(read_text(e.path()) == read_text(other)) << e.path().filename() << " differs";
    ++compared;
  }
  EXPECT_EQ(compared, 6);  // 5 frames and monitors.csv
}

// Runs the CLI with `args`; expects a non-zero exit and `message` in what it printed.
void expect_refused(const std::string& args, const std::string& message) {
  const auto r = run_command(cli() + " " + args);
  EXPECT_NE(r.exit_code, 0) << args << '\n' << r.output;
  EXPECT_NE(r.output.find(message), std::string::npos)
      << "phymul " << args << " lacks: " << message << "\ngot:\n"
      << r.output;
}

TEST(Robustness, ArgumentErrorsExitNonZeroWithAClearMessage) {
  expect_refused("", "A subcommand is required");
  expect_refused("frobnicate", "unknown command 'frobnicate' (expected one of run, check");
  expect_refused("run", "scene is required");
  expect_refused("truthcube --cells 0", "--cells");
}

TEST(Robustness, OutputOntoARegularFileIsRefusedNamingIt) {
  TempDir dir;
  const auto scene = dir.path() / "jelly.yaml";
  std::ofstream(scene) << kShortScene;
  const auto file = dir.path() / "taken";
  std::ofstream(file) << "not a directory";
  const auto r = run_command(cli() + " run " + scene.string() + " -o " + file.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("'" + file.string() + "' exists and is not a directory"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(read_text(file), "not a directory");
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// dt three times the stability estimate: the runaway guard stops the run in the step where
// the growth appears, with finite numbers everywhere, exit code 3, the last good state as the
// final frame and monitor row, and report.json saying why.
TEST(Robustness, ThreeTimesTheStableStepIsStoppedByTheRunawayGuard) {
  TempDir dir;
  std::string text = R"(simulation:
  dt: DT
  duration: 1 s
  gravity: [0, 0, -9.81]
  damping: 2 1/s
objects:
  - name: jelly
    mesh: {generator: box, size: [2 cm, 2 cm, 2 cm], cells: [4, 4, 4]}
    material: {stiffness: 50 N/m, density: 1000 kg/m^3}
    volume_constraint: true
constraints:
  - {type: fixed, object: jelly, nodes: top}
output:
  interval: 0.01 s
)";
  const auto scene = dir.path() / "jelly.yaml";
  std::ofstream(scene) << text;
  // The stability estimate as `check` reports it (dt auto is half of it).
  std::string dt_text = std::string(text).replace(text.find("DT"), 2, "auto");
  std::ofstream(scene) << dt_text;
  const auto checked = run_command(cli() + " check " + scene.string());
  ASSERT_EQ(checked.exit_code, 0) << checked.output;
  const auto at = checked.output.find("stable estimate ");
  ASSERT_NE(at, std::string::npos) << checked.output;
  const double stable = std::stod(checked.output.substr(at + 16));
  ASSERT_GT(stable, 1e-4);
  std::ofstream(scene) << std::string(text).replace(text.find("DT"), 2,
                                                    std::to_string(3.0 * stable) + " s");
  const auto out = dir.path() / "out";
  const auto r = run_command(cli() + " run -q " + scene.string() + " -o " + out.string());
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("a runaway, caught before any number overflowed"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("of component 'jelly'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the stability estimate is"), std::string::npos) << r.output;
  const std::string report = read_text(out / "report.json");
  EXPECT_NE(report.find("\"status\": \"unstable\""), std::string::npos) << report;
  EXPECT_NE(report.find("runaway"), std::string::npos) << report;
  EXPECT_EQ(report.find("null"), std::string::npos) << report;  // every number finite
  // No non-finite number in any file; the last frame is the last good state.
  for (const auto& e : fs::directory_iterator(out)) {
    const std::string body = read_text(e.path());
    EXPECT_EQ(body.find("nan"), std::string::npos) << e.path();
    EXPECT_EQ(body.find("inf"), std::string::npos) << e.path();
  }
  const std::string pvd = read_text(out / "jelly.pvd");
  const auto last = pvd.rfind("timestep=\"");
  const double last_frame = std::stod(pvd.substr(last + 10));
  const auto t = report.find("\"simulated_time_s\": ");
  EXPECT_EQ(last_frame, std::stod(report.substr(t + 20)));
  EXPECT_GT(last_frame, 0.0);
  EXPECT_LT(last_frame, 10 * 3.0 * stable);  // within a few steps of the start
}

}  // namespace
}  // namespace phymul
