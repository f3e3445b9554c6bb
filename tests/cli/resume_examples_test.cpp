// Every scene in examples/ resumes bit for bit: run whole, then interrupted by a real SIGINT
// part way and resumed, and killed by SIGKILL after a periodic checkpoint and resumed; the
// frames, monitors.csv and report.json (wall-clock fields aside) are the uninterrupted run's,
// byte for byte. Static runs are interrupted at every progress check (so within load steps
// and between them). The signals come from this test while the run is held
// stopped at a known step (--pause-after: SIGSTOP there), so that none arrives too late.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "phymul/checkpoint.hpp"
#include "support/process.hpp"
#include "support/results.hpp"

namespace phymul {
namespace {

namespace fs = std::filesystem;
using testing::expect_same_results;
using testing::read_text;
using testing::TempDir;

// The scenes CMake found in examples/ (tests/CMakeLists.txt), relative to it.
std::vector<std::string> example_scenes() {
  std::vector<std::string> scenes;
  std::istringstream in(PHYMUL_EXAMPLE_SCENES);
  for (std::string scene; std::getline(in, scene, ',');) scenes.push_back(scene);
  return scenes;
}

// The list is the directory as it is: a scene added since the build was configured fails
// here rather than going untested. examples/sweeps holds sweep files (phymul sweep), not scenes.
TEST(ResumeExamples, EveryExampleSceneIsTested) {
  std::vector<std::string> found;
  const fs::path root = testing::source_dir() / "examples";
  for (const auto& e : fs::recursive_directory_iterator(root)) {
    const std::string name = fs::relative(e.path(), root).string();
    if (e.path().extension() == ".yaml" && !name.starts_with("sweeps/")) found.push_back(name);
  }
  std::sort(found.begin(), found.end());
  EXPECT_EQ(found, example_scenes());
  EXPECT_GE(found.size(), 20u);
}

long report_integer(const fs::path& dir, const std::string& key) {
  std::smatch m;
  const std::string text = read_text(dir / "report.json");
  if (!std::regex_search(text, m, std::regex("\"" + key + "\": (-?[0-9]+)"))) return -1;
  return std::stol(m[1]);
}

// Runs `phymul run -q args...`, held with SIGSTOP where --pause-after puts it, then sends it
// `signal` (and SIGCONT); the exit status, or -signal when a signal ended it.
int run_signalled(const std::vector<std::string>& args, int signal) {
  std::vector<std::string> all{testing::cli(), "run", "-q"};
  all.insert(all.end(), args.begin(), args.end());
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, WUNTRACED);
  if (WIFSTOPPED(status)) {
    kill(pid, signal);
    kill(pid, SIGCONT);
    waitpid(pid, &status, 0);
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}

int run_plain(const std::string& args) {
  const auto r = testing::run_command(testing::cli() + " run -q " + args);
  if (r.exit_code != 0) ADD_FAILURE() << args << ":\n" << r.output;
  return r.exit_code;
}

// Steps (dynamic), relaxation iterations (static) or Newton iterations the checkpoint is at.
long progress_of(const Checkpoint& c) {
  if (c.newton.load_steps_done > 0) return c.newton.newton_iterations;
  if (c.static_mode)
    return c.data.static_progress.iterations + c.data.static_progress.step_iterations;
  return c.steps_done;
}

class ResumeExample : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    scene_ = (testing::source_dir() / "examples" / GetParam()).string();
    full_ = dir_.path() / "full";
    ASSERT_EQ(run_plain(scene_ + " -o " + full_.string()), 0);
    steps_ = report_integer(full_, "steps");
    static_ = read_text(full_ / "report.json").find("\"mode\": \"static\"") != std::string::npos;
    ASSERT_GT(steps_, 4) << "the example is too short to interrupt";
  }
  void interrupt_by_sigint_and_resume();
  void kill_after_a_periodic_checkpoint_and_resume();
  void interrupt_kill_and_resume();
  TempDir dir_;
  std::string scene_;
  fs::path full_;
  long steps_ = 0;
  bool static_ = false;
};

// Static runs: SIGINT at every progress check, each time resumed.
void ResumeExample::interrupt_by_sigint_and_resume() {
  const fs::path part = dir_.path() / "sigint";
  std::set<std::string> stops;  // where the interruptions fell
  long pause = 1;
  for (int round = 0;; ++round) {
    ASSERT_LT(round, 200) << "the run never ended";
    std::vector<std::string> args{"--resume", part.string()};
    if (round == 0) args = {scene_, "-o", part.string()};
    args.insert(args.end(), {"--pause-after", std::to_string(pause)});
    const int exit = run_signalled(args, SIGINT);
    if (exit == 0) break;
    ASSERT_EQ(exit, 130) << "round " << round;
    const Checkpoint c = read_checkpoint(part / "checkpoint.bin");
    EXPECT_GE(progress_of(c), pause);
    stops.insert(c.data.static_progress.step_iterations > 0 ? "within" : "between");
    pause = progress_of(c) + 1;
  }
  EXPECT_FALSE(stops.empty()) << "never interrupted";
  expect_same_results(full_, part);
}

// Static runs: SIGKILL after a periodic checkpoint, then resumed. They check (and so
// checkpoint) only every 256 relaxation iterations and at the end of load steps: every check
// writes one with --checkpoint-every 1.
void ResumeExample::kill_after_a_periodic_checkpoint_and_resume() {
  const fs::path part = dir_.path() / "sigkill";
  const long pause = steps_ * 3 / 5;
  const int exit = run_signalled({scene_, "-o", part.string(), "--checkpoint-every", "1 steps",
                                  "--pause-after", std::to_string(pause)},
                                 SIGKILL);
  ASSERT_EQ(exit, -SIGKILL);
  ASSERT_TRUE(fs::is_regular_file(part / "checkpoint.bin"));
  const long at = progress_of(read_checkpoint(part / "checkpoint.bin"));
  EXPECT_GT(at, 0);
  EXPECT_LT(at, pause);  // the periodic one before the kill
  ASSERT_EQ(run_plain("--resume " + part.string()), 0);
  expect_same_results(full_, part);
}

// Dynamic runs, one chain: SIGINT 40 % of the way; resumed with periodic checkpoints and
// killed by SIGKILL at 80 %, after the one at 65 %; resumed again to the end. Two resumes for
// little more than one run's time (the examples' runs are most of the sanitized suite's).
void ResumeExample::interrupt_kill_and_resume() {
  const fs::path part = dir_.path() / "chain";
  const long first = steps_ * 2 / 5, second = steps_ * 4 / 5, every = std::max(1L, steps_ / 4);
  ASSERT_EQ(
      run_signalled({scene_, "-o", part.string(), "--pause-after", std::to_string(first)}, SIGINT),
      130);
  EXPECT_EQ(read_checkpoint(part / "checkpoint.bin").steps_done, first);
  ASSERT_EQ(
      run_signalled({"--resume", part.string(), "--checkpoint-every",
                     std::to_string(every) + " steps", "--pause-after", std::to_string(second)},
                    SIGKILL),
      -SIGKILL);
  const long at = read_checkpoint(part / "checkpoint.bin").steps_done;
  EXPECT_GT(at, first);  // the resumed run's periodic one, before the kill
  EXPECT_LT(at, second);
  ASSERT_EQ(run_plain("--resume " + part.string()), 0);
  expect_same_results(full_, part);
}

// One test per example, so that the uninterrupted run is made once.
TEST_P(ResumeExample, InterruptedOrKilledAndResumedWritesTheSameFiles) {
  if (!static_) {
    interrupt_kill_and_resume();
    return;
  }
  {
    SCOPED_TRACE("SIGINT at every progress check, each time --resume");
    interrupt_by_sigint_and_resume();
  }
  SCOPED_TRACE("SIGKILL after a periodic checkpoint, then --resume");
  kill_after_a_periodic_checkpoint_and_resume();
}

INSTANTIATE_TEST_SUITE_P(Examples, ResumeExample, ::testing::ValuesIn(example_scenes()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param;
                           for (char& ch : name)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return name;
                         });

}  // namespace
}  // namespace phymul
