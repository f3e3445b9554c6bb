// Running a scene to files: frames (.vtu + .pvd), monitors.csv and report.json.
#pragma once

#include <filesystem>
#include <string>

#include "phymul/model.hpp"
#include "phymul/scene.hpp"

namespace phymul {

// How often a run writes its checkpoint (output_dir/checkpoint.bin); both zero: only when
// interrupted.
struct CheckpointInterval {
  long steps = 0;     // explicit steps (dynamic) or relaxation iterations (static)
  double time = 0.0;  // s of simulated time (dynamic mode only)
};

// "500 steps" or a simulated time with its unit ("0.2 s", "50 ms"). Throws
// std::invalid_argument with a message naming the text and what is expected.
CheckpointInterval parse_checkpoint_interval(const std::string& text);

struct RunOptions {
  std::filesystem::path output_dir;
  bool progress = false;  // a progress line on stderr (the CLI turns it on for terminals)
  CheckpointInterval checkpoint_every;
  // Continue from output_dir's checkpoint; the scene must be the one it was run from
  // (same bytes), and the results then match the uninterrupted run's bit for bit.
  bool resume = false;
  // For tests: behave as if interrupted after this many steps (dynamic) or at the first
  // progress check at or after this many relaxation iterations (static); 0: never.
  long stop_after_steps = 0;
  // For tests of real signals: stop the process (SIGSTOP) once, where stop_after_steps would
  // stop the run, so that a test can send it SIGINT or SIGKILL at a known step; 0: never.
  long pause_after_steps = 0;
};

// A needle's tip through a tissue's surface (report.json's "needle_punctures").
struct NeedlePuncture {
  std::string needle, object;
  double time = 0.0;   // s
  double depth = 0.0;  // m
  double force = 0.0;  // N, the push along the shaft that broke through
};

struct RunReport {
  std::string status = "completed";  // completed | unstable | not-converged | interrupted
  std::string message;
  std::string mode = "dynamic";  // dynamic | static
  long steps = 0;                // explicit steps, or static relaxation iterations
  double simulated_time = 0.0;   // s
  double wall_time = 0.0;        // s
  double ns_per_node_per_step = 0.0;
  // Dynamic mode: simulated seconds per wall-clock second, output included (steps per second
  // x dt); real time when >= 1.
  double real_time_factor = 0.0;
  // Dynamic mode: the wall-clock time inside the steps alone (s), and the simulated seconds
  // per second of it: what an interactive loop that writes no files gets.
  double step_wall_time = 0.0;
  double stepping_real_time_factor = 0.0;
  double dt = 0.0, stable_dt = 0.0;  // s
  int nodes = 0;
  int threads = 1;  // OpenMP threads the run used
  int frames = 0;
  bool converged = false;  // static mode
  double residual = 0.0;   // N, static mode: final largest residual force
  // Static mode with `solver: newton` (report.json has these only then): Newton iterations
  // (also in `steps`), converged load steps, and the sum of the support reactions and of the
  // applied loads (gravity and forces) at the last equilibrium, which balance.
  bool newton = false;
  int load_steps_done = 0, load_steps = 0;
  Eigen::Vector3d support_reaction = Eigen::Vector3d::Zero();  // N
  Eigen::Vector3d applied_load = Eigen::Vector3d::Zero();      // N
  // Shape-memory objects given `young` (report.json has "stiffness_from_young" only then).
  std::vector<StiffnessCalibration> stiffness_calibrations;
  // Scenes with needles (report.json has "needle_punctures" only then).
  bool needles = false;
  std::vector<NeedlePuncture> punctures;
};

// Compiles and runs the scene, writing into options.output_dir (created if missing; a
// std::runtime_error naming it if it exists and is not a directory).
// Throws SceneError for input problems; instability ends the run with status "unstable",
// the last good frame written and the report saying what happened. An interruption request
// (below) ends it after the current step (dynamic) or at the next progress check of the
// static relaxation (every 256 iterations and at the end of each load step), with a final
// frame and status "interrupted".
// An interrupted run (and one with a checkpoint interval) leaves output_dir/checkpoint.bin;
// a run that ends otherwise removes it. Checkpoint problems (missing, corrupt, another
// scene) throw CheckpointError.
RunReport run_scene(const Scene& scene, const RunOptions& options);

// The scene file that the checkpoint in output_dir was run from (absolute path).
std::filesystem::path checkpointed_scene(const std::filesystem::path& output_dir);

// Interruption: SIGINT and SIGTERM handlers that set an async-signal-safe flag which
// run_scene checks; a second signal of the same kind takes its default action (ends the
// process at once).
void install_interrupt_handlers();
void request_interrupt() noexcept;  // what the handlers do: sets the flag
void clear_interrupt() noexcept;
bool interrupt_requested() noexcept;

}  // namespace phymul
