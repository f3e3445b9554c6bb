// Checkpoint and resume: a run stopped part way (by --stop-after, a signal or SIGKILL) and
// resumed writes the same files, byte for byte, as the run never stopped.
#include "phymul/checkpoint.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>

#include "support/needle_scene.hpp"
#include "support/process.hpp"
#include "support/results.hpp"

namespace phymul {
namespace {

namespace fs = std::filesystem;
using testing::cli;
using testing::expect_same_results;
using testing::read_text;
using testing::run_command;
using testing::TempDir;

// Damped dynamics with a volume constraint, gravity and a frame interval that does not
// divide the step count: every piece of state the loop carries matters.
std::string dynamic_scene(const std::string& integrator) {
  return R"(simulation:
  dt: auto
  duration: 0.3 s
  integrator: )" +
         integrator + R"(
  gravity: [0, 0, -9.81]
  damping: 6 1/s
objects:
  - name: cube
    mesh: {generator: box, element: hexa, size: [4 cm, 4 cm, 4 cm], cells: [4, 4, 4]}
    volume_constraint: true
    material: {stiffness: 200 N/m, density: 1000 kg/m^3, frame: polar}
constraints:
  - {type: fixed, object: cube, nodes: top}
output:
  interval: 0.037 s
)";
}

// Load steps, kinetic damping and a prescribed displacement: the static solve's progress.
constexpr const char* kStaticScene = R"(simulation:
  mode: static
  duration: 1 s
  load_steps: 3
  tolerance: 1e-6 N
  max_iterations: 200000
objects:
  - name: cube
    mesh: {generator: box, element: hexa, size: [40 mm, 40 mm, 40 mm], cells: [4, 4, 4]}
    material: {stiffness: 20 N/m, density: 1000 kg/m^3}
    volume_constraint: true
constraints:
  - {type: fixed, object: cube, nodes: bottom}
  - type: displacement
    object: cube
    nodes: top
    axes: xyz
    schedule:
      - {t: 0 s, value: [0, 0, 0]}
      - {t: 1 s, value: [0, 0, -6 mm]}
)";

fs::path write_scene(const TempDir& dir, const std::string& text,
                     const std::string& name = "scene.yaml") {
  const fs::path p = dir.path() / name;
  std::ofstream(p) << text;
  return p;
}

testing::ProcessResult phymul(const std::string& args) {
  return run_command(cli() + " run -q " + args);
}

int count_frames(const fs::path& dir) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.path().extension() == ".vtu";
  return n;
}

class DynamicResume : public ::testing::TestWithParam<std::string> {};

TEST_P(DynamicResume, StoppedTwiceAndResumedMatchesTheUninterruptedRunByteForByte) {
  TempDir dir;
  const fs::path scene = write_scene(dir, dynamic_scene(GetParam()));
  const fs::path full = dir.path() / "full", part = dir.path() / "part";
  const auto r0 = phymul(scene.string() + " -o " + full.string());
  ASSERT_EQ(r0.exit_code, 0) << r0.output;
  EXPECT_FALSE(fs::exists(full / "checkpoint.bin"));
  EXPECT_GE(count_frames(full), 9);  // t = 0, 8 intervals of 0.037 s, the end

  const auto r1 = phymul(scene.string() + " -o " + part.string() + " --stop-after 137");
  ASSERT_EQ(r1.exit_code, 130) << r1.output;
  ASSERT_TRUE(fs::is_regular_file(part / "checkpoint.bin"));
  EXPECT_EQ(read_checkpoint(part / "checkpoint.bin").steps_done, 137);
  EXPECT_NE(read_text(part / "report.json").find("\"interrupted\""), std::string::npos);
  // A second stop further on, then the rest.
  const auto r2 = phymul("--resume " + part.string() + " --stop-after 300");
  ASSERT_EQ(r2.exit_code, 130) << r2.output;
  EXPECT_EQ(read_checkpoint(part / "checkpoint.bin").steps_done, 300);
  const auto r3 = phymul("--resume " + part.string());
  ASSERT_EQ(r3.exit_code, 0) << r3.output;
  expect_same_results(full, part);
}

// (The implicit steps refactorise their matrix on resuming: a fresh workspace, the same bits.)
INSTANTIATE_TEST_SUITE_P(Integrators, DynamicResume,
                         ::testing::Values("verlet", "newton-cotes", "implicit"));

TEST(Checkpoint, StaticRunStoppedInALoadStepAndResumedMatchesByteForByte) {
  TempDir dir;
  const fs::path scene = write_scene(dir, kStaticScene);
  const fs::path full = dir.path() / "full", part = dir.path() / "part";
  const auto r0 = phymul(scene.string() + " -o " + full.string());
  ASSERT_EQ(r0.exit_code, 0) << r0.output;
  const auto r1 = phymul(scene.string() + " -o " + part.string() + " --stop-after 600");
  ASSERT_EQ(r1.exit_code, 130) << r1.output;
  const Checkpoint c = read_checkpoint(part / "checkpoint.bin");
  ASSERT_TRUE(c.static_mode);
  // Stopped inside a load step, with kinetic damping under way: the hard case.
  EXPECT_GE(c.data.static_progress.load_step, 1);
  EXPECT_GT(c.data.static_progress.step_iterations, 0);
  const auto r2 = phymul("--resume " + part.string());
  ASSERT_EQ(r2.exit_code, 0) << r2.output;
  expect_same_results(full, part);
}

// The pressed block example (a Gmsh mesh file) converges each load step in fewer than 256
// iterations: it stops, and checkpoints, between load steps.
TEST(Checkpoint, StaticRunStoppedBetweenLoadStepsAndResumedMatchesByteForByte) {
  TempDir dir;
  const fs::path examples = testing::source_dir() / "examples";
  fs::create_directories(dir.path() / "meshes");
  fs::copy_file(examples / "meshes/block.msh", dir.path() / "meshes/block.msh");
  const fs::path scene = dir.path() / "block.yaml";
  fs::copy_file(examples / "pressed_block.yaml", scene);
  const fs::path full = dir.path() / "full", part = dir.path() / "part";
  const auto r0 = phymul(scene.string() + " -o " + full.string());
  ASSERT_EQ(r0.exit_code, 0) << r0.output;
  long after = 1;  // iterations, all load steps together
  for (int stop = 0; stop < 2; ++stop) {
    const auto r = phymul((stop == 0 ? scene.string() + " -o " : "--resume ") + part.string() +
                          " --stop-after " + std::to_string(after));
    ASSERT_EQ(r.exit_code, 130) << r.output;
    const Checkpoint c = read_checkpoint(part / "checkpoint.bin");
    EXPECT_EQ(c.data.static_progress.load_step, stop + 1);
    EXPECT_EQ(c.data.static_progress.step_iterations, 0);
    EXPECT_GT(c.data.static_progress.iterations, after - 1);
    after = c.data.static_progress.iterations + 1;
  }
  const auto r1 = phymul("--resume " + part.string());
  ASSERT_EQ(r1.exit_code, 0) << r1.output;
  expect_same_results(full, part);
}

TEST(Checkpoint, SigintWritesACheckpointThatResumesToTheSameResults) {
  TempDir dir;
  // Long enough for the signal to arrive part way.
  std::string text = dynamic_scene("verlet");
  text.replace(text.find("duration: 0.3 s"), 15, "duration: 1 s");
  text.replace(text.find("cells: [4, 4, 4]"), 16, "cells: [6, 6, 6]");
  const fs::path scene = write_scene(dir, text);
  const fs::path part = dir.path() / "part", full = dir.path() / "full";
  const std::string exe = cli(), scene_s = scene.string(), part_s = part.string();
  const pid_t pid = fork();
  if (pid == 0) {
    execl(exe.c_str(), exe.c_str(), "run", "-q", scene_s.c_str(), "-o", part_s.c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  ASSERT_GT(pid, 0);
  // Wait for the first frames, so the signal comes in the middle of the stepping.
  for (int i = 0; i < 3000 && !fs::exists(part / "scene_000002.vtu"); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  if (WEXITSTATUS(status) == 0) GTEST_SKIP() << "the run ended before the signal arrived";
  ASSERT_EQ(WEXITSTATUS(status), 130);
  const long stopped = read_checkpoint(part / "checkpoint.bin").steps_done;
  EXPECT_GT(stopped, 0);
  // The reference: the same run stopped at the same step by the test switch, then both go on
  // to the end.
  const auto r0 = phymul(scene.string() + " -o " + full.string());
  ASSERT_EQ(r0.exit_code, 0) << r0.output;
  const auto r1 = phymul("--resume " + part.string());
  ASSERT_EQ(r1.exit_code, 0) << r1.output;
  expect_same_results(full, part);
}

TEST(Checkpoint, PeriodicCheckpointSurvivesSigkill) {
  TempDir dir;
  std::string text = dynamic_scene("verlet");
  text.replace(text.find("duration: 0.3 s"), 15, "duration: 1000 s");
  const fs::path scene = write_scene(dir, text);
  const fs::path part = dir.path() / "part", reference = dir.path() / "reference";
  const std::string exe = cli(), scene_s = scene.string(), part_s = part.string();
  const pid_t pid = fork();
  if (pid == 0) {
    execl(exe.c_str(), exe.c_str(), "run", "-q", scene_s.c_str(), "-o", part_s.c_str(),
          "--checkpoint-every", "0.01 s", static_cast<char*>(nullptr));
    _exit(127);
  }
  ASSERT_GT(pid, 0);
  for (int i = 0; i < 6000 && !fs::exists(part / "checkpoint.bin"); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  kill(pid, SIGKILL);  // no chance to clean up
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(fs::is_regular_file(part / "checkpoint.bin"));
  const Checkpoint c = read_checkpoint(part / "checkpoint.bin");
  // Checkpoints at multiples of 0.01 s of simulated time (to within half a step).
  const double dt = c.data.dt;
  const double phase = std::remainder(c.data.time, 0.01);
  EXPECT_LT(std::abs(phase), dt) << "checkpoint at t = " << c.data.time;
  // Resumed and the uninterrupted run, both stopped 50 steps further: the same files.
  const std::string stop = " --stop-after " + std::to_string(c.steps_done + 50);
  const auto r0 = phymul(scene.string() + " -o " + reference.string() + stop);
  ASSERT_EQ(r0.exit_code, 130) << r0.output;
  const auto r1 = phymul("--resume " + part.string() + stop);
  ASSERT_EQ(r1.exit_code, 130) << r1.output;
  expect_same_results(reference, part);
}

TEST(Checkpoint, ResumeRefusesAChangedScene) {
  TempDir dir;
  const fs::path scene = write_scene(dir, dynamic_scene("verlet"));
  const fs::path part = dir.path() / "part";
  ASSERT_EQ(phymul(scene.string() + " -o " + part.string() + " --stop-after 20").exit_code, 130);
  std::ofstream(scene, std::ios::app) << "# edited\n";
  const auto r = phymul("--resume " + part.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("changed since the checkpoint"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(scene.string()), std::string::npos) << r.output;
}

TEST(Checkpoint, ResumeRefusesAChangedMeshFile) {
  TempDir dir;
  const fs::path examples = testing::source_dir() / "examples";
  fs::create_directories(dir.path() / "meshes");
  fs::copy_file(examples / "meshes/block.msh", dir.path() / "meshes/block.msh");
  // A tolerance tight enough for a load step to pass the 256-iteration progress check.
  std::string text = read_text(examples / "pressed_block.yaml");
  text.replace(text.find("tolerance: 1e-6 N"), 17, "tolerance: 1e-11 N");
  const fs::path scene = write_scene(dir, text, "block.yaml");
  const fs::path part = dir.path() / "part";
  ASSERT_EQ(phymul(scene.string() + " -o " + part.string() + " --stop-after 256").exit_code, 130);
  // The same file with one coordinate moved by 1 um (1e-3 in its millimetres).
  std::string mesh = read_text(dir.path() / "meshes/block.msh");
  const auto at = mesh.find("-20.0 -20.0 0.0\n");
  ASSERT_NE(at, std::string::npos);
  mesh.replace(at, 15, "-20.001 -20.0 0.0");
  std::ofstream(dir.path() / "meshes/block.msh") << mesh;
  const auto r = phymul("--resume " + part.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("differs from the checkpoint's"), std::string::npos) << r.output;
}

// A checkpoint that cannot be written (here its name is taken by a directory) costs a
// warning, not the run's results.
TEST(Checkpoint, AnUnwritableCheckpointWarnsAndTheRunGoesOn) {
  TempDir dir;
  const fs::path scene = write_scene(dir, dynamic_scene("verlet"));
  const fs::path out = dir.path() / "out";
  fs::create_directories(out / "checkpoint.bin" / "taken");
  const auto r = phymul(scene.string() + " -o " + out.string() + " --checkpoint-every '20 steps'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("the run goes on without a checkpoint"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("without a checkpoint", r.output.find("without a checkpoint") + 1),
            std::string::npos)
      << "warned more than once:\n"
      << r.output;
  EXPECT_NE(read_text(out / "report.json").find("\"completed\""), std::string::npos);
  EXPECT_GE(count_frames(out), 9);
}

TEST(Checkpoint, ResumeWithoutACheckpointSaysWhy) {
  TempDir dir;
  const fs::path scene = write_scene(dir, dynamic_scene("verlet"));
  const fs::path full = dir.path() / "full";
  ASSERT_EQ(phymul(scene.string() + " -o " + full.string()).exit_code, 0);
  const auto r = phymul("--resume " + full.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("no checkpoint at"), std::string::npos) << r.output;
}

TEST(Checkpoint, BadIntervalIsRefusedWithTheAcceptedForms) {
  TempDir dir;
  const fs::path scene = write_scene(dir, dynamic_scene("verlet"));
  for (const char* bad : {"'0 steps'", "'-1 s'", "'10 kg'", "'often'"}) {
    const auto r = phymul(scene.string() + " -o " + (dir.path() / "o").string() +
                          " --checkpoint-every " + bad);
    EXPECT_EQ(r.exit_code, 1) << bad << r.output;
    EXPECT_NE(r.output.find("--checkpoint-every"), std::string::npos) << r.output;
  }
  const fs::path statics = write_scene(dir, kStaticScene, "static.yaml");
  const auto r =
      phymul(statics.string() + " -o " + (dir.path() / "s").string() + " --checkpoint-every '1 s'");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("relaxation iterations"), std::string::npos) << r.output;
}

// Damaged checkpoint files: a clear message naming the file, exit code 1, never a crash.
class DamagedCheckpoint : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = write_scene(dir_, dynamic_scene("verlet"));
    part_ = dir_.path() / "part";
    ASSERT_EQ(phymul(scene_.string() + " -o " + part_.string() + " --stop-after 30").exit_code,
              130);
    bytes_ = read_text(part_ / "checkpoint.bin");
    ASSERT_GT(bytes_.size(), 1000u);
  }
  void expect_refused(const std::string& bytes, const std::string& expected) {
    std::ofstream(part_ / "checkpoint.bin", std::ios::binary | std::ios::trunc) << bytes;
    const auto r = phymul("--resume " + part_.string() + " " + scene_.string());
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(expected), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("checkpoint.bin"), std::string::npos) << r.output;
  }
  TempDir dir_;
  fs::path scene_, part_;
  std::string bytes_;
};

TEST_F(DamagedCheckpoint, Truncated) {
  expect_refused(bytes_.substr(0, bytes_.size() / 2), "truncated");
  expect_refused(bytes_.substr(0, 20), "truncated");
}

TEST_F(DamagedCheckpoint, FlippedByte) {
  std::string b = bytes_;
  b[b.size() / 2] ^= 0x40;
  expect_refused(b, "checksum does not match");
}

TEST_F(DamagedCheckpoint, NotACheckpoint) {
  expect_refused("", "not a phymul checkpoint");
  expect_refused("time_s,kinetic_energy_J\n0,0\n", "not a phymul checkpoint");
}

TEST_F(DamagedCheckpoint, OtherVersion) {
  std::string b = bytes_;
  b[8] = 99;
  expect_refused(b, "format version 99");
}

// Every prefix and many single-byte corruptions parse to CheckpointError, never a crash or a
// wrong acceptance; corruptions inside the payload that keep the checksum are caught by the
// field checks (here: forged by recomputing the checksum).
TEST(CheckpointFormat, EveryPrefixAndForgedFieldIsRefused) {
  Checkpoint c;
  c.scene_file = "/tmp/scene.yaml";
  c.data.dt = 1e-3;
  c.data.x.assign(3, Vec3(1, 2, 3));
  c.data.v.assign(3, Vec3::Zero());
  c.data.f.assign(3, Vec3::Zero());
  c.data.rotation.assign(2, Eigen::Quaterniond::Identity());
  c.frames = {{0.0, "scene_000000.vtu"}};
  c.monitors = "time_s\n0\n";
  TempDir dir;
  write_checkpoint(dir.path() / "c.bin", c);
  const std::string bytes = read_text(dir.path() / "c.bin");
  const Checkpoint back = parse_checkpoint(bytes, "c.bin");
  EXPECT_EQ(back.data.x, c.data.x);
  EXPECT_EQ(back.frames.size(), 1u);
  EXPECT_EQ(back.monitors, c.monitors);
  for (size_t n = 0; n < bytes.size(); ++n)
    EXPECT_THROW(parse_checkpoint(bytes.substr(0, n), "c.bin"), CheckpointError) << n;
  // Forge: a count field far too large, with a valid checksum.
  constexpr size_t kHeader = 32;
  std::string body = bytes.substr(kHeader, bytes.size() - kHeader - 8);
  // scene_file (length, bytes), two hashes, static_mode, then data's time and step: |x|.
  const size_t x_count = 8 + c.scene_file.size() + 8 * 3 + 8 + 8;
  for (uint64_t huge : {uint64_t(1) << 62, uint64_t(4), uint64_t(0)}) {
    std::string forged = body;
    std::memcpy(forged.data() + x_count, &huge, 8);
    const uint64_t sum = fnv1a(forged);
    std::string file = bytes.substr(0, kHeader) + forged;
    file.append(reinterpret_cast<const char*>(&sum), 8);
    EXPECT_THROW(parse_checkpoint(file, "c.bin"), CheckpointError) << huge;
  }
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// The muscle example: a free rigid bone (quaternion, momenta) lifted by active fibres. A
// resumed run must restore the bodies too, or the bone restarts from rest.
TEST(Checkpoint, RigidBodiesAndFibresResumeByteForByte) {
  TempDir dir;
  const fs::path scene = testing::source_dir() / "examples" / "muscle.yaml";
  const fs::path full = dir.path() / "full", part = dir.path() / "part";
  ASSERT_EQ(phymul(scene.string() + " -o " + full.string()).exit_code, 0);
  const auto r1 = phymul(scene.string() + " -o " + part.string() + " --stop-after 12001");
  ASSERT_EQ(r1.exit_code, 130) << r1.output;
  const auto r2 = phymul("--resume " + part.string());
  ASSERT_EQ(r2.exit_code, 0) << r2.output;
  expect_same_results(full, part);
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// A needle in implicit steps stopped after its puncture, with a track sliding and sticking:
// the needle's state (phases, track, anchors) is all a step starts from.
TEST(Checkpoint, ImplicitNeedleStepsResumeTheTrack) {
  TempDir dir;
  testing::BlockScene block;
  block.integrator = "integrator: implicit, dt: 2 ms, implicit_tolerance: 1e-9 N";
  std::string text = block.yaml();
  text.replace(text.find("duration: 4 s"), 13, "duration: 1.6 s");
  const fs::path scene = write_scene(dir, text + "output:\n  interval: 0.1 s\n");
  const fs::path full = dir.path() / "full", part = dir.path() / "part";
  ASSERT_EQ(phymul(scene.string() + " -o " + full.string()).exit_code, 0);
  const auto r1 = phymul(scene.string() + " -o " + part.string() + " --stop-after 700");
  ASSERT_EQ(r1.exit_code, 130) << r1.output;
  const NeedleState saved = read_checkpoint(part / "checkpoint.bin").data.needles.at(0);
  EXPECT_EQ(saved.punctures.size(), 1u);
  EXPECT_GE(saved.track.size(), 2u);
  const auto r2 = phymul("--resume " + part.string());
  ASSERT_EQ(r2.exit_code, 0) << r2.output;
  expect_same_results(full, part);
}

// A cantilever of explicit finite elements bending under its weight in implicit steps.
const char* const kImplicitCantilever = R"(simulation:
  integrator: implicit
  dt: 5 ms
  duration: 0.4 s
  damping: 10 1/s
  implicit_tolerance: 1e-9 N
  gravity: [0, 0, -9.81 m/s^2]
objects:
  - name: beam
    mesh: {generator: box, element: hexa, size: [100 mm, 20 mm, 20 mm], cells: [10, 2, 2],
           center: [50 mm, 0, 0]}
    material: {model: fem, young: 100 kPa, poisson: 0.45, density: 1000 kg/m^3}
constraints:
  - {type: fixed, object: beam, nodes: left}
output:
  interval: 0.05 s
)";

// Implicit steps on finite elements refactorise P as the cells turn (Data::cell_rotation): the
// cantilever bending under its weight, stopped after the first refactorisations, resumes to
// the same bits (and fails to without its Anderson history, Data::anderson: checked).
TEST(Checkpoint, ImplicitFiniteElementsResumeWithTheirTurnedMatrix) {
  TempDir dir;
  const fs::path scene = write_scene(dir, kImplicitCantilever);
  const fs::path full = dir.path() / "full", part = dir.path() / "part";
  ASSERT_EQ(phymul(scene.string() + " -o " + full.string()).exit_code, 0);
  const auto r1 = phymul(scene.string() + " -o " + part.string() + " --stop-after 23");
  ASSERT_EQ(r1.exit_code, 130) << r1.output;
  double turned = 0.0;
  for (const Eigen::Quaterniond& q : read_checkpoint(part / "checkpoint.bin").data.cell_rotation)
    turned = std::max(turned, q.angularDistance(Eigen::Quaterniond::Identity()));
  EXPECT_GT(turned, 0.04);  // P was turned at least twice
  // The iterations' Anderson history goes on into the next step: the resumed run's too.
  EXPECT_GT(read_checkpoint(part / "checkpoint.bin").data.anderson.count, 0);
  const auto r2 = phymul("--resume " + part.string());
  ASSERT_EQ(r2.exit_code, 0) << r2.output;
  expect_same_results(full, part);
}

// A checkpoint whose Anderson history claims more columns than it keeps: exit 1 naming the
// member and its range, no crash.
TEST(Checkpoint, AnAndersonHistoryOutOfItsRingIsRefusedByName) {
  TempDir dir;
  const fs::path scene = write_scene(dir, kImplicitCantilever);
  const fs::path part = dir.path() / "part";
  ASSERT_EQ(phymul(scene.string() + " -o " + part.string() + " --stop-after 5").exit_code, 130);
  Checkpoint c = read_checkpoint(part / "checkpoint.bin");
  ASSERT_EQ(c.data.anderson.df.size(), 5 * c.data.x.size());
  c.data.anderson.count = 7;
  write_checkpoint(part / "checkpoint.bin", c);
  const auto r = phymul("--resume " + part.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("'data.anderson.count' is 7, expected 0 to 5"), std::string::npos)
      << r.output;
}

// A checkpoint whose data lacks an array the model needs (as version 1 files lacked the
// obstacles' contact forces, on which a resumed run crashed): exit 1 naming the member, no
// crash.
TEST(Checkpoint, DataThatDoesNotFitTheModelIsRefusedByName) {
  TempDir dir;
  const fs::path scene = testing::source_dir() / "examples" / "probe.yaml";
  const fs::path part = dir.path() / "part";
  ASSERT_EQ(phymul(scene.string() + " -o " + part.string() + " --stop-after 100").exit_code, 130);
  Checkpoint c = read_checkpoint(part / "checkpoint.bin");
  ASSERT_FALSE(c.data.contact_force.empty());
  c.data.contact_force.clear();
  write_checkpoint(part / "checkpoint.bin", c);
  const auto r = phymul("--resume " + part.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("'data.contact_force' has 0 entries where the model has 1"),
            std::string::npos)
      << r.output;
}

}  // namespace
}  // namespace phymul
