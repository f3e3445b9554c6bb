// Running a scene to files: frames (.vtu + .pvd), monitors.csv and report.json.
#pragma once

#include <filesystem>
#include <string>

#include "phymul/scene.hpp"

namespace phymul {

struct RunOptions {
  std::filesystem::path output_dir;
  bool progress = false;  // a progress line on stderr (the CLI turns it on for terminals)
};

struct RunReport {
  std::string status = "completed";  // completed | unstable | not-converged | interrupted
  std::string message;
  std::string mode = "dynamic";  // dynamic | static
  long steps = 0;                // explicit steps, or static relaxation iterations
  double simulated_time = 0.0;   // s
  double wall_time = 0.0;        // s
  double ns_per_node_per_step = 0.0;
  double dt = 0.0, stable_dt = 0.0;  // s
  int nodes = 0;
  int frames = 0;
  bool converged = false;  // static mode
  double residual = 0.0;   // N, static mode: final largest residual force
};

// Compiles and runs the scene, writing into options.output_dir (created if missing; a
// std::runtime_error naming it if it exists and is not a directory).
// Throws SceneError for input problems; instability ends the run with status "unstable",
// the last good frame written and the report saying what happened. An interruption request
// (below) ends it after the current step (dynamic) or at the next progress check of the
// static relaxation (every 256 iterations), with a final frame and status "interrupted".
RunReport run_scene(const Scene& scene, const RunOptions& options);

// Interruption: SIGINT and SIGTERM handlers that set an async-signal-safe flag which
// run_scene checks; a second signal of the same kind takes its default action (ends the
// process at once).
void install_interrupt_handlers();
void request_interrupt() noexcept;  // what the handlers do: sets the flag
void clear_interrupt() noexcept;
bool interrupt_requested() noexcept;

}  // namespace phymul
