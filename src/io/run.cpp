#include "phymul/run.hpp"

#include <fmt/format.h>
#include <omp.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <optional>
#include <stdexcept>

#include "io/needle_output.hpp"
#include "io/run_checkpoint.hpp"
#include "io/run_newton.hpp"
#include "io/units.hpp"

namespace phymul {
namespace {

// Set from signal handlers: only a volatile sig_atomic_t store is async-signal-safe.
volatile std::sig_atomic_t g_interrupt = 0;

extern "C" void on_interrupt_signal(int) { g_interrupt = 1; }

// Thrown from the static relaxation's progress callback to stop it between iterations.
struct Interrupted {};

class ProgressLine {
 public:
  explicit ProgressLine(bool on) : on_(on) {}
  ~ProgressLine() {
    if (on_ && shown_) std::fputs("\n", stderr);
  }
  void show(double fraction, const std::string& detail, bool force = false) {
    if (!on_) return;
    const auto now = std::chrono::steady_clock::now();
    if (!force && shown_ && now - last_ < std::chrono::milliseconds(200)) return;
    last_ = now;
    shown_ = true;
    const int width = 30, filled = int(std::clamp(fraction, 0.0, 1.0) * width);
    std::fprintf(stderr, "\r[%s%s] %3.0f%%  %s   ", std::string(size_t(filled), '=').c_str(),
                 std::string(size_t(width - filled), ' ').c_str(), 100.0 * fraction,
                 detail.c_str());
    std::fflush(stderr);
  }

 private:
  bool on_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point last_{};
};

// What the two modes' loops share.
struct Run {
  const Scene& scene;
  const RunOptions& options;
  Simulator& sim;
  ResultWriter& out;
  RunReport& report;
  ProgressLine& progress;
  CheckpointWriter checkpoints;
  StopCheck stop_requested;

  void save_checkpoint(long steps_done, double next_frame) {
    Checkpoint c;
    c.steps_done = steps_done;
    c.next_frame = next_frame;
    checkpoints.save(std::move(c), sim, out);
  }
};

void run_static(Run& run, const Checkpoint* from) {
  Simulator& sim = run.sim;
  const SimulationSpec& settings = sim.model().settings;
  RunReport& report = run.report;
  report.mode = "static";
  StaticResult r;
  CheckpointClock clock(run.options.checkpoint_every, sim.data().step, 0.0);
  bool interrupted = !from && interrupt_requested();
  if (interrupted) run.save_checkpoint(0, 0.0);
  if (!interrupted) {
    const auto check = [&](long, double residual) {
      const StaticProgress& p = sim.data().static_progress;
      const long total = p.iterations + p.step_iterations;
      const bool stop = run.stop_requested(total);
      if (stop || clock.due(total, 0.0, 0.0)) run.save_checkpoint(0, 0.0);
      if (stop) throw Interrupted{};
      run.progress.show(double(total) / double(settings.max_iterations),
                        fmt::format("iteration {}  residual {:.3g} N", total, residual));
    };
    try {
      r = from ? sim.resume_static(check) : sim.solve_static(check);
    } catch (const Interrupted&) {
      interrupted = true;
    }
  }
  report.steps = interrupted ? sim.data().step : r.iterations;
  report.converged = interrupted ? false : r.converged;
  report.residual = interrupted ? sim.max_residual_force() : r.residual;
  if (interrupted) {
    report.status = "interrupted";
    report.message = interrupted_message(run.options.output_dir);
  } else if (!r.converged) {
    report.status = "not-converged";
    report.message = fmt::format(
        "no equilibrium after {} iterations: the largest residual force is {:.3g} N, above "
        "the tolerance {:.3g} N; raise max_iterations or load_steps, or add damping",
        r.iterations, r.residual, settings.tolerance);
  }
  run.out.monitor(sim);
  run.out.frame(sim);
}

// Whole steps that land exactly on the duration, none larger than the chosen dt: sets that
// dt and returns their number.
long set_whole_steps(Simulator& sim) {
  const double duration = sim.model().settings.duration;
  const long steps = std::max(1L, long(std::ceil(duration / sim.dt() - 1e-9)));
  sim.set_dt(duration / double(steps));
  return steps;
}

void run_dynamic(Run& run, const Checkpoint* from, long steps) {
  Simulator& sim = run.sim;
  const SimulationSpec& settings = sim.model().settings;
  RunReport& report = run.report;
  ResultWriter& out = run.out;
  const double interval = run.scene.output.interval;
  double next_frame = from ? from->next_frame : interval > 0 ? interval : settings.duration;
  // A monitor row computes the residual force (about 15 % of a step on the prostate study):
  // 500 rows draw any run's history, where a row every other step cost real time.
  const long monitor_every = std::max(1L, steps / 500);
  long done = from ? from->steps_done : 0;
  CheckpointClock clock(run.options.checkpoint_every, done, sim.data().time);
  double stepping = 0.0;  // s of wall-clock time inside sim.step()
  for (long k = done + 1; k <= steps; ++k) {
    const auto before = std::chrono::steady_clock::now();
    sim.step();
    stepping += std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
    done = k;
    const double t = sim.data().time;
    const bool monitored = k % monitor_every == 0 || k == steps;
    const bool framed = k == steps || t >= next_frame - 0.5 * sim.dt();
    if (monitored) out.monitor(sim);
    if (framed) {
      out.frame(sim);
      while (next_frame <= t + 0.5 * sim.dt()) next_frame += interval > 0 ? interval : 1e300;
    }
    if (k == steps) break;
    // The checkpoint holds what the uninterrupted run writes up to here; an interruption
    // then adds this step's monitor row and frame, which resuming overwrites.
    const bool stop = run.stop_requested(k);
    if (clock.due(k, t, sim.dt()) || stop) run.save_checkpoint(k, next_frame);
    if (stop) {
      if (!monitored) out.monitor(sim);
      if (!framed) out.frame(sim);
      break;
    }
    if ((k & 63) == 0)
      run.progress.show(double(k) / double(steps), fmt::format("t = {:.4g} s  step {}", t, k));
  }
  run.progress.show(double(done) / double(steps),
                    fmt::format("t = {:.4g} s  step {}", sim.data().time, done), true);
  report.steps = done;
  report.step_wall_time = stepping;
  report.residual = sim.max_residual_force();
  report.converged = done == steps;
  if (done < steps) {
    report.status = "interrupted";
    report.message = interrupted_message(run.options.output_dir);
  }
}

}  // namespace

CheckpointInterval parse_checkpoint_interval(const std::string& text) {
  long steps = 0;
  char tail[16] = {};
  if (std::sscanf(text.c_str(), "%ld %15s", &steps, tail) == 2 &&
      (std::string(tail) == "steps" || std::string(tail) == "step")) {
    if (steps < 1)
      throw std::invalid_argument(
          fmt::format("--checkpoint-every '{}': the number of steps must be 1 or more", text));
    return {steps, 0.0};
  }
  const io::QuantityResult t = io::parse_quantity(text, io::Dimension::time, "--checkpoint-every");
  if (!t.value || !(*t.value > 0))
    throw std::invalid_argument(fmt::format(
        "--checkpoint-every '{}': expected a number of steps ('500 steps') or a positive "
        "simulated time with its unit ('0.2 s', '50 ms'){}",
        text, t.error.empty() ? "" : " (" + t.error + ")"));
  return {0, *t.value};
}

std::filesystem::path checkpointed_scene(const std::filesystem::path& output_dir) {
  return read_checkpoint(checkpoint_path(output_dir)).scene_file;
}

void request_interrupt() noexcept { g_interrupt = 1; }
void clear_interrupt() noexcept { g_interrupt = 0; }
bool interrupt_requested() noexcept { return g_interrupt != 0; }

void install_interrupt_handlers() {
  struct sigaction action {};
  action.sa_handler = on_interrupt_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;  // a second signal ends the process at once
  for (int sig : {SIGINT, SIGTERM})
    if (sigaction(sig, &action, nullptr) != 0)
      throw std::runtime_error(fmt::format("cannot install the handler for signal {}", sig));
}

RunReport run_scene(const Scene& scene, const RunOptions& options) {
  std::error_code ec;
  if (std::filesystem::exists(options.output_dir, ec) &&
      !std::filesystem::is_directory(options.output_dir, ec))
    throw std::runtime_error(fmt::format("output directory '{}' exists and is not a directory",
                                         options.output_dir.string()));
  if (scene.simulation.mode == SolveMode::static_equilibrium &&
      scene.simulation.solver == StaticSolver::newton)
    return run_newton(scene, options);
  const std::uint64_t scene_hash = file_hash(scene.file);
  const std::optional<Checkpoint> from = checkpoint_to_resume(scene, options, scene_hash);
  Simulator sim(compile_scene(scene));
  const Model& model = sim.model();
  const std::uint64_t model_id = model_hash(model);
  const bool static_mode = model.settings.mode == SolveMode::static_equilibrium;
  if (options.checkpoint_every.time > 0 && static_mode)
    throw std::invalid_argument(
        "--checkpoint-every: a static run counts relaxation iterations, not simulated time; "
        "give a number of steps, e.g. '--checkpoint-every 5000 steps'");
  const long steps = static_mode ? 0 : set_whole_steps(sim);
  if (from) check_checkpoint_model(*from, model, scene, options);
  if (from && (from->static_mode != static_mode || from->data.dt != sim.dt() ||
               (!static_mode && from->steps_done >= steps)))
    throw CheckpointError(fmt::format(
        "cannot resume in {}: the checkpoint is of a {} run of dt {} s at step {}, this one {} "
        "with dt {} s ({} steps); start a new run",
        options.output_dir.string(), from->static_mode ? "static" : "dynamic", from->data.dt,
        from->steps_done, static_mode ? "static" : "dynamic", sim.dt(), steps));
  std::filesystem::create_directories(options.output_dir);
  ResultWriter out(options.output_dir, scene.file.stem().string(), model, scene.output.vtk,
                   scene.output.format);

  RunReport report;
  report.nodes = model.node_count();
  report.stiffness_calibrations = model.stiffness_calibrations;
  report.threads = omp_get_max_threads();
  report.dt = sim.dt();
  report.stable_dt = sim.stable_dt();
  ProgressLine progress(options.progress);
  Run run{scene,
          options,
          sim,
          out,
          report,
          progress,
          CheckpointWriter{scene, options, scene_hash, model_id},
          StopCheck(options)};
  const auto start = std::chrono::steady_clock::now();
  start_or_restore(from ? &*from : nullptr, sim, out);
  try {
    if (static_mode)
      run_static(run, from ? &*from : nullptr);
    else
      run_dynamic(run, from ? &*from : nullptr, steps);
  } catch (const InstabilityError& e) {
    report.status = "unstable";
    report.message = e.what();
    report.steps = sim.data().step;
    report.residual = sim.max_residual_force();
    // The step that failed was undone: write the last good state, unless it is written.
    const double t = sim.data().time;
    if (out.monitored_time() != t) out.monitor(sim);
    if (out.frame_list().empty() || out.frame_list().back().time != t) out.frame(sim);
  }
  report.wall_time =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.simulated_time = sim.data().time;
  report.frames = out.frames();
  report.needles = !model.needles.empty();
  report.punctures = needle_punctures(model, sim.data());
  const long steps_here = sim.data().step - (from ? from->data.step : 0);
  if (steps_here > 0)
    report.ns_per_node_per_step =
        report.wall_time * 1e9 / (double(steps_here) * double(report.nodes));
  const double simulated_here = sim.data().time - (from ? from->data.time : 0.0);
  if (!static_mode && report.wall_time > 0.0)
    report.real_time_factor = simulated_here / report.wall_time;
  if (!static_mode && report.step_wall_time > 0.0)
    report.stepping_real_time_factor = simulated_here / report.step_wall_time;
  if (report.status != "interrupted")
    std::filesystem::remove(checkpoint_path(options.output_dir), ec);
  out.finish(report);
  return report;
}

}  // namespace phymul
