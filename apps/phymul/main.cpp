// phymul command line: thin, parses arguments and calls the library.
#include <fmt/format.h>
#include <omp.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>

#include "commands.hpp"
#include "phymul/model.hpp"
#include "phymul/run.hpp"
#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"

namespace {

// Exit codes a script can tell apart.
constexpr int kInputError = 1;
constexpr int kUnstable = 3;
constexpr int kNotConverged = 4;
constexpr int kInterrupted = 130;  // 128 + SIGINT, as shells report a Ctrl-C

int report_scene_error(const phymul::SceneError& e) {
  for (const auto& d : e.diagnostics()) std::cerr << d.str() << '\n';
  std::cerr << fmt::format("{} problem(s) found\n", e.diagnostics().size());
  return kInputError;
}

// What a scene's `young` made of a shape-memory K, and how near the FEM that leaves it.
void print_stiffness_calibrations(const std::vector<phymul::StiffnessCalibration>& calibrations) {
  for (const phymul::StiffnessCalibration& c : calibrations)
    std::cout << fmt::format(
        "  object '{}': K = {:.4g} N/m from E = {:.4g} Pa, nu = {:g} (alpha = K/(E h) = {:.3g}, "
        "h = {:.3g} mm): compressed {:g} % along {} ({} and {} nodes clamped), the FEM takes "
        "{:.4g} N; the displacements differ by {:.1f} % of the push rms, {:.1f} % at most\n",
        c.component, c.stiffness, c.young, c.poisson, c.alpha, c.h * 1e3, c.strain * 100,
        "xyz"[c.axis], c.held, c.pushed, c.fem_force, c.displacement_rms * 100,
        c.displacement_max * 100);
}

int check(const std::string& file) {
  try {
    const phymul::Scene scene = phymul::load_scene(file);
    const phymul::Model model = phymul::compile_scene(scene);
    for (const phymul::ObjectSpec& o : scene.objects)  // what reading a surface repaired
      for (const std::string& note : o.mesh.file_notes) std::cout << "  " << note << '\n';
    for (const std::string& note : scene.notes) std::cout << "  " << note << '\n';
    print_stiffness_calibrations(model.stiffness_calibrations);
    if (scene.simulation.solver == phymul::StaticSolver::newton) {  // no time step to speak of
      std::cout << fmt::format("{}: ok ({} objects, {} nodes, {} cells; static, Newton)\n", file,
                               model.components.size(), model.node_count(), model.cells.size());
      return 0;
    }
    phymul::Simulator sim(model);
    std::cout << fmt::format(
        "{}: ok ({} objects, {} nodes, {} cells; dt {:.3g} s, stable "
        "estimate {:.3g} s)\n",
        file, model.components.size(), model.node_count(), model.cells.size(), sim.dt(),
        sim.stable_dt());
    return 0;
  } catch (const phymul::SceneError& e) {
    return report_scene_error(e);
  }
}

struct RunArguments {
  std::string scene, out = "out", checkpoint_every, resume;
  std::string format;  // empty: the scene's output.format
  bool quiet = false;
  int threads = 0;                       // 0: OpenMP's default (OMP_NUM_THREADS, else every core)
  long stop_after = 0, pause_after = 0;  // hidden, for tests
};

int run(RunArguments a) {
  try {
    phymul::RunOptions options;
    options.progress = !a.quiet && isatty(fileno(stderr));
    if (a.threads > 0) omp_set_num_threads(a.threads);
    options.stop_after_steps = a.stop_after;
    options.pause_after_steps = a.pause_after;
    if (!a.checkpoint_every.empty())
      options.checkpoint_every = phymul::parse_checkpoint_interval(a.checkpoint_every);
    if (!a.resume.empty()) {
      options.resume = true;
      a.out = a.resume;
      if (a.scene.empty()) a.scene = phymul::checkpointed_scene(a.resume).string();
    }
    options.output_dir = a.out;
    const std::string& file = a.scene;
    const std::string& out = a.out;
    const bool quiet = a.quiet;
    phymul::Scene scene = phymul::load_scene(file);
    if (!a.format.empty())
      scene.output.format =
          a.format == "binary" ? phymul::VtuEncoding::binary : phymul::VtuEncoding::ascii;
    phymul::install_interrupt_handlers();
    const phymul::RunReport r = phymul::run_scene(scene, options);
    if (!quiet && r.newton)
      std::cout << fmt::format(
          "{}: {} after {} of {} load steps, {} Newton iterations ({:.3g} s wall); {} frames in "
          "{}\n",
          file, r.status, r.load_steps_done, r.load_steps, r.steps, r.wall_time, r.frames, out);
    else if (!quiet)
      std::cout << fmt::format(
          "{}: {} after {} steps ({:.4g} s simulated, {:.3g} s wall, {:.1f} ns/node/step); "
          "{} frames in {}\n",
          file, r.status, r.steps, r.simulated_time, r.wall_time, r.ns_per_node_per_step, r.frames,
          out);
    if (!quiet) print_stiffness_calibrations(r.stiffness_calibrations);
    if (r.status == "unstable") {
      std::cerr << "error: " << r.message << '\n';
      return kUnstable;
    }
    if (r.status == "not-converged") {
      std::cerr << "error: " << r.message << '\n';
      return kNotConverged;
    }
    if (r.status == "interrupted") {
      std::cerr << fmt::format(
          "{}: stopped after {} steps ({:.4g} s simulated); {} frames in {}\n{}\n", file, r.steps,
          r.simulated_time, r.frames, out, r.message);
      return kInterrupted;
    }
    return 0;
  } catch (const phymul::SceneError& e) {
    return report_scene_error(e);
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"phymul: soft organs and their surroundings (Phymul local shape memory model)"};
  app.require_subcommand(1);
  std::string scene_file;
  RunArguments run_args;

  auto* run_cmd = app.add_subcommand("run", "simulate a scene and write its results");
  run_cmd->add_option("scene", run_args.scene,
                      "scene file (YAML); with --resume, the one the checkpoint records");
  auto* output =
      run_cmd->add_option("-o,--output", run_args.out, "output directory")->capture_default_str();
  run_cmd->add_flag("-q,--quiet", run_args.quiet, "no progress and no summary");
  run_cmd
      ->add_option("--format", run_args.format,
                   "how the .vtu frames hold their numbers, instead of the scene's "
                   "output.format: ascii (text) or binary (raw appended data, same bits)")
      ->check(CLI::IsMember({"ascii", "binary"}));
  run_cmd
      ->add_option("--threads", run_args.threads,
                   "threads (default: OMP_NUM_THREADS, else every core); results are the same "
                   "bit for bit whatever their number")
      ->check(CLI::Range(1, 1024));
  run_cmd->add_option("--checkpoint-every", run_args.checkpoint_every,
                      "write DIR/checkpoint.bin every N steps ('500 steps') or simulated "
                      "time ('0.2 s'); an interrupted run writes one anyway");
  run_cmd
      ->add_option("--resume", run_args.resume,
                   "continue the interrupted run in DIR from its checkpoint (same results, bit "
                   "for bit, as never interrupted)")
      ->excludes(output);
  run_cmd->add_option("--stop-after", run_args.stop_after)->group("");  // tests: as if interrupted
  run_cmd->add_option("--pause-after", run_args.pause_after)->group("");  // tests: SIGSTOP there

  auto* check_cmd = app.add_subcommand("check", "validate a scene without running it");
  check_cmd->add_option("scene", scene_file, "scene file (YAML)")->required();

  app.add_subcommand("schema", "print the scene file reference (Markdown)");
  const auto truthcube = phymul::cli::add_truthcube_command(app);
  const auto calibrate = phymul::cli::add_calibrate_command(app);
  const auto prostate = phymul::cli::add_prostate_command(app);
  const auto sweep = phymul::cli::add_sweep_command(app);
  const auto mesh = phymul::cli::add_mesh_command(app);
  const auto serve = phymul::cli::add_serve_command(app);
  const auto export_pml = phymul::cli::add_export_pml_command(app);

  // CLI11 alone reports an unknown command as "A subcommand is required": name it instead.
  if (argc > 1 && argv[1][0] != '-') {
    std::string known;
    bool found = false;
    for (const CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
      found = found || sub->check_name(argv[1]);
      known += (known.empty() ? "" : ", ") + sub->get_name();
    }
    if (!found) {
      std::cerr << fmt::format(
          "error: unknown command '{}' (expected one of {}); run with --help\n", argv[1], known);
      return kInputError;
    }
  }
  CLI11_PARSE(app, argc, argv);
  try {
    if (*run_cmd) {
      if (run_args.scene.empty() && run_args.resume.empty()) {
        std::cerr << "error: run: scene is required (a scene file, or --resume DIR to continue a "
                     "run); run with --help\n";
        return kInputError;
      }
      return run(run_args);
    }
    if (*check_cmd) return check(scene_file);
    if (*truthcube.app) return truthcube.run();
    if (*calibrate.app) return calibrate.run();
    if (*prostate.app) return prostate.run();
    if (*sweep.app) return sweep.run();
    if (*mesh.app) return mesh.run();
    if (*serve.app) return serve.run();
    if (*export_pml.app) return export_pml.run();
    std::cout << phymul::scene_reference_markdown();
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return kInputError;
  }
}
