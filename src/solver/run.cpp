#include "phymul/run.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "io/results.hpp"
#include "phymul/simulator.hpp"

namespace phymul {
namespace {

// Set from signal handlers: only a volatile sig_atomic_t store is async-signal-safe.
volatile std::sig_atomic_t g_interrupt = 0;

extern "C" void on_interrupt_signal(int) { g_interrupt = 1; }

// Thrown from the static relaxation's progress callback to stop it between iterations.
struct Interrupted {};

constexpr const char* kInterruptedMessage =
    "interrupted by a signal; the results up to the last step are written";

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

}  // namespace

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
  Simulator sim(compile_scene(scene));
  const Model& model = sim.model();
  const SimulationSpec& settings = model.settings;
  std::filesystem::create_directories(options.output_dir);
  ResultWriter out(options.output_dir, scene.file.stem().string(), model, scene.output.vtk);

  RunReport report;
  report.nodes = model.node_count();
  report.dt = sim.dt();
  report.stable_dt = stable_time_step(model);
  ProgressLine progress(options.progress);
  const auto start = std::chrono::steady_clock::now();
  out.frame(sim);
  out.monitor(sim);
  try {
    if (settings.mode == SolveMode::static_equilibrium) {
      report.mode = "static";
      StaticResult r;
      bool interrupted = interrupt_requested();
      if (!interrupted) {
        try {
          r = sim.solve_static([&](long it, double residual) {
            if (interrupt_requested()) throw Interrupted{};
            progress.show(double(it) / double(settings.max_iterations),
                          fmt::format("iteration {}  residual {:.3g} N", it, residual));
          });
        } catch (const Interrupted&) {
          interrupted = true;
        }
      }
      report.steps = interrupted ? sim.state().step : r.iterations;
      report.converged = interrupted ? false : r.converged;
      report.residual = interrupted ? sim.max_residual_force() : r.residual;
      if (interrupted) {
        report.status = "interrupted";
        report.message = kInterruptedMessage;
      } else if (!r.converged) {
        report.status = "not-converged";
        report.message = fmt::format(
            "no equilibrium after {} iterations: the largest residual force is {:.3g} N, above "
            "the tolerance {:.3g} N; raise max_iterations or load_steps, or add damping",
            r.iterations, r.residual, settings.tolerance);
      }
      out.monitor(sim);
      out.frame(sim);
    } else {
      // Whole steps that land exactly on the duration, none larger than the chosen dt.
      const long steps = std::max(1L, long(std::ceil(settings.duration / sim.dt() - 1e-9)));
      sim.set_dt(settings.duration / double(steps));
      report.dt = sim.dt();
      const double interval = scene.output.interval;
      double next_frame = interval > 0 ? interval : settings.duration;
      const long monitor_every = std::max(1L, steps / 2000);
      long done = 0;
      for (long k = 1; k <= steps; ++k) {
        sim.step();
        done = k;
        const double t = sim.state().time;
        // Interrupted: this step is the last one, with its monitor row and its frame.
        const bool last = k == steps || interrupt_requested();
        if (k % monitor_every == 0 || last) out.monitor(sim);
        if (last || t >= next_frame - 0.5 * sim.dt()) {
          out.frame(sim);
          while (next_frame <= t + 0.5 * sim.dt()) next_frame += interval > 0 ? interval : 1e300;
        }
        if (last) break;
        if ((k & 63) == 0)
          progress.show(double(k) / double(steps), fmt::format("t = {:.4g} s  step {}", t, k));
      }
      progress.show(double(done) / double(steps),
                    fmt::format("t = {:.4g} s  step {}", sim.state().time, done), true);
      report.steps = done;
      report.residual = sim.max_residual_force();
      report.converged = done == steps;
      if (done < steps) {
        report.status = "interrupted";
        report.message = kInterruptedMessage;
      }
    }
  } catch (const InstabilityError& e) {
    report.status = "unstable";
    report.message = e.what();
    report.steps = sim.state().step;
  }
  report.wall_time =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.simulated_time = sim.state().time;
  report.frames = out.frames();
  if (report.steps > 0)
    report.ns_per_node_per_step =
        report.wall_time * 1e9 / (double(report.steps) * double(report.nodes));
  out.finish(report);
  return report;
}

}  // namespace phymul
