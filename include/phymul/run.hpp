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
  std::string status = "completed";  // completed | unstable | not-converged
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

// Compiles and runs the scene, writing into options.output_dir (created if missing).
// Throws SceneError for input problems; instability ends the run with status "unstable",
// the last good frame written and the report saying what happened.
RunReport run_scene(const Scene& scene, const RunOptions& options);

}  // namespace phymul
