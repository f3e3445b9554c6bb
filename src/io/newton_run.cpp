// run_scene's route to the reference finite elements (io/run_newton.hpp).
#include <fmt/format.h>
#include <omp.h>

#include <chrono>
#include <cstdio>
#include <stdexcept>

#include "io/run_checkpoint.hpp"
#include "io/run_newton.hpp"

namespace phymul {

namespace {

// The equilibrium of a load step into the simulator's state, which the writers read: the
// force on a node is minus the reaction (Data::f holds every force on it, the supports'
// excepted, so support_reactions() = -f on the held axes).
void set_state(Simulator& sim, const std::vector<Vec3>& u, const std::vector<Vec3>& reaction,
               double time) {
  Data& s = sim.data();
  const Model& m = sim.model();
  for (int i = 0; i < m.node_count(); ++i) {
    s.x[size_t(i)] = m.rest_position[size_t(i)] + u[size_t(i)];
    s.v[size_t(i)].setZero();
    s.f[size_t(i)] = -reaction[size_t(i)];
  }
  s.time = time;
}

void sum_reactions(const Model& model, const fem::Problem& problem, const fem::Result& result,
                   double load_factor, RunReport& report) {
  std::vector<std::array<bool, 3>> held(model.rest_position.size(), {false, false, false});
  for (const fem::Dirichlet& d : problem.prescribed) held[size_t(d.node)][size_t(d.axis)] = true;
  report.support_reaction.setZero();
  for (size_t i = 0; i < held.size(); ++i)
    for (int a = 0; a < 3; ++a)
      if (held[i][size_t(a)]) report.support_reaction[a] += result.reaction[i][a];
  report.applied_load.setZero();
  for (const Vec3& f : problem.nodal_force) report.applied_load += load_factor * f;
}

// The fem state a resume starts from must be of this problem's size.
void check_solve_state(const fem::SolveState& state, const Model& model, const Scene& scene,
                       const RunOptions& options) {
  if (state.load_steps_done < 1 || state.displacement.size() != 3 * model.rest_position.size())
    throw CheckpointError(fmt::format(
        "cannot resume in {}: the checkpoint holds no Newton solve of the model compiled from {} "
        "(it was written by a relaxation run, another phymul, or is damaged); start a new run",
        options.output_dir.string(), scene.file.string()));
}

fem::Result solve(const Scene& scene, const fem::Problem& problem) {
  try {
    return fem::solve_static(problem);
  } catch (const std::invalid_argument& e) {  // what the scene checks do not catch
    throw SceneError({{scene.simulation.loc.line > 0 ? scene.simulation.loc
                                                     : SourceLoc{scene.file.string(), 0, 0},
                       e.what()}});
  }
}

}  // namespace

RunReport run_newton(const Scene& scene, const RunOptions& options) {
  if (options.checkpoint_every.time > 0)
    throw std::invalid_argument(
        "--checkpoint-every: a static Newton run counts Newton iterations, not simulated time; "
        "give a number of steps, e.g. '--checkpoint-every 10 steps' (it checkpoints at the end "
        "of a load step once that many iterations have passed)");
  const std::uint64_t scene_hash = file_hash(scene.file);
  const std::optional<Checkpoint> from = checkpoint_to_resume(scene, options, scene_hash);
  Simulator sim(compile_scene(scene));
  const Model& model = sim.model();
  fem::Problem problem = newton_problem(model);
  if (from) {
    check_checkpoint_model(*from, model, scene, options);
    check_solve_state(from->newton, model, scene, options);
    problem.resume_from = from->newton;
  }
  std::filesystem::create_directories(options.output_dir);
  ResultWriter out(options.output_dir, scene.file.stem().string(), model, scene.output.vtk,
                   scene.output.format);
  RunReport report;
  report.mode = "static";
  report.newton = true;
  report.load_steps = problem.load_steps;
  report.nodes = model.node_count();
  report.threads = omp_get_max_threads();
  start_or_restore(from ? &*from : nullptr, sim, out);
  CheckpointWriter checkpoints{scene, options, scene_hash, model_hash(model)};
  StopCheck stop_requested(options);
  CheckpointClock clock(options.checkpoint_every, from ? from->newton.newton_iterations : 0, 0.0);
  const double duration = scene.simulation.duration;
  const auto start = std::chrono::steady_clock::now();
  problem.on_load_step = [&](const fem::LoadStepReport& r) {
    set_state(sim, r.displacement, r.reaction, duration * r.step / r.steps);
    out.monitor(sim);
    out.frame(sim);
    if (options.progress)
      std::fprintf(stderr, "load step %d of %d: %d Newton iterations, residual %.3g N\n", r.step,
                   r.steps, r.newton_iterations, r.residual);
    if (r.step == r.steps) return true;  // nothing left to stop for
    const bool stop = stop_requested(r.newton_iterations);
    if (stop || clock.due(r.newton_iterations, 0.0, 0.0)) {
      Checkpoint c;
      c.newton = r.state;
      checkpoints.save(std::move(c), sim, out);
    }
    return !stop;
  };
  const fem::Result result = solve(scene, problem);
  report.wall_time =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report.steps = result.newton_iterations;
  report.load_steps_done = result.load_steps_done;
  report.converged = result.converged;
  report.residual = result.final_residual;
  report.simulated_time = duration * result.load_steps_done / problem.load_steps;
  report.frames = out.frames();
  sum_reactions(model, problem, result, double(result.load_steps_done) / problem.load_steps,
                report);
  if (result.stopped) {
    report.status = "interrupted";
    report.message = fmt::format("after load step {} of {}: {}", result.load_steps_done,
                                 problem.load_steps, interrupted_message(options.output_dir));
  } else if (!result.converged) {
    report.status = "not-converged";
    report.message = fmt::format(
        "{}. The frames hold the {} converged load step(s) of {}; raise load_steps, or check "
        "that the constraints hold the objects (a free rigid motion has no equilibrium)",
        result.message, result.load_steps_done, problem.load_steps);
  }
  if (report.status != "interrupted") {
    std::error_code ec;
    std::filesystem::remove(checkpoint_path(options.output_dir), ec);
  }
  out.finish(report);
  return report;
}

}  // namespace phymul
