#include <fmt/format.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "phymul/run.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/scene_words.hpp"
#include "phymul/simulation.hpp"
#include "phymul/studies/prostate.hpp"
#include "phymul/vtk.hpp"
#include "pictures.hpp"

namespace phymul::cli {
namespace {

struct Settings {
  prostate::Options study;
  std::vector<double> fillings_ml{50, 100, 200, 300, 400};
  std::string probe = "both", model = "lsm", neck, dt_estimate, support = "lateral",
              static_solver = "relaxation", relaxation = "fire";
  double force = 0, lift_mm = 0, young_kpa = 0, mass_scaling_us = -1, stitch_radius_mm = 0;
  int bladder_subdivisions = 0;
  std::string output = "results/prostate", json_file, scenes;
  bool no_realtime = false, no_pictures = false, quiet = false, coarse = false;
};

double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// Every scene of the study in explicit dynamics on one thread, timed against the clock, each
// in real_time/<name>/ (its scene.yaml, frames and report.json).
std::vector<prostate::RealTimeRun> real_time_runs(const Settings& s) {
  omp_set_num_threads(1);  // the measure: real time on one core
  std::vector<prostate::RealTimeRun> runs;
  for (double filling : s.study.fillings)
    for (prostate::Probe probe : s.study.probes) {
      const prostate::SceneSettings scene = prostate::dynamic_scene(s.study, filling, probe);
      const std::filesystem::path dir =
          std::filesystem::path(s.output) / "real_time" / prostate::run_name(filling, probe);
      std::filesystem::create_directories(dir);
      const std::string text = prostate::scene_text(s.study, scene);
      write_file_atomically(dir / "scene.yaml", [&](std::ostream& o) { o << text; });
      RunOptions options;
      options.output_dir = dir;
      options.progress = false;
      const Scene spec = load_scene(dir / "scene.yaml");
      const double cpu_start = process_cpu_seconds();
      const RunReport r = run_scene(spec, options);
      const double cpu = process_cpu_seconds() - cpu_start;
      if (r.status != "completed")
        throw std::runtime_error(fmt::format(
            "real-time run {}: {} ({})", prostate::run_name(filling, probe), r.status, r.message));
      const Simulator sim(compile_scene(spec));
      double mass = 0.0;
      for (double m : sim.model().mass) mass += m;
      runs.push_back({filling, probe, r.steps, r.dt, r.wall_time, r.real_time_factor,
                      r.simulated_time / cpu, r.stepping_real_time_factor,
                      100.0 * sim.added_inertia() / mass});
    }
  return runs;
}

int run(Settings& s) {
  if (s.coarse) s.study = prostate::coarse_bladder(s.study);
  prostate::Options& o = s.study;
  o.fillings.clear();
  for (double ml : s.fillings_ml) o.fillings.push_back(ml * 1e-6);
  if (s.probe == "pressure") o.probes = {prostate::Probe::pressure};
  if (s.probe == "rigid") o.probes = {prostate::Probe::rigid};
  if (s.model == "fem") o.prostate_model = ElasticModel::fem;
  if (s.neck == "prostate") o.neck = prostate::Neck::prostate;
  if (s.neck == "bladder") o.neck = prostate::Neck::bladder;
  if (s.support == "bladder") o.support = prostate::Support::bladder;
  if (s.bladder_subdivisions > 0) o.bladder_subdivisions = s.bladder_subdivisions;
  if (s.force > 0) o.probe_force = s.force;
  if (s.lift_mm > 0) o.probe_lift = s.lift_mm * 1e-3;
  if (s.stitch_radius_mm > 0) o.stitch_radius = s.stitch_radius_mm * 1e-3;
  if (s.young_kpa > 0) o.prostate_young = s.young_kpa * 1e3;
  if (s.mass_scaling_us >= 0) o.mass_scaling_dt = s.mass_scaling_us * 1e-6;
  if (const auto estimate = scene_value<DtEstimate>(s.dt_estimate)) o.dt_estimate = *estimate;
  o.static_solver = *scene_value<StaticSolver>(s.static_solver);
  o.relaxation = *scene_value<Relaxation>(s.relaxation);
  try {
    if (!s.scenes.empty()) {  // the study's scenes, in dynamics, for `phymul run`
      std::filesystem::create_directories(s.scenes);
      for (double filling : o.fillings)
        for (prostate::Probe p : o.probes) {
          const prostate::SceneSettings scene = prostate::dynamic_scene(o, filling, p);
          const auto file =
              std::filesystem::path(s.scenes) / (prostate::run_name(filling, p) + ".yaml");
          write_file_atomically(file,
                                [&](std::ostream& f) { f << prostate::scene_text(o, scene); });
        }
      return 0;
    }
    const bool show = !s.quiet && isatty(fileno(stderr));
    prostate::Study study =
        prostate::run_study(o, s.output, [show](int done, int total, const std::string& name) {
          if (show)
            std::cerr << fmt::format("\rprostate: run {}/{} ({})      ", done + 1, total, name);
        });
    if (show) std::cerr << "\r" << std::string(60, ' ') << "\r";
    std::cout << prostate::table(study);
    if (!s.no_realtime) {
      study.real_time = real_time_runs(s);
      study.real_time_factor = study.real_time.front().real_time_factor;
      for (const prostate::RealTimeRun& r : study.real_time) {
        study.real_time_factor = std::min(study.real_time_factor, r.real_time_factor);
        std::cout << fmt::format(
            "real time: {:.0f} mL {} in dynamics, 1 thread: {} steps of {:.3g} s in {:.3g} s, "
            "{:.2f}x real time ({:.2f}x by CPU time, {:.2f}x stepping alone; mass scaling "
            "+{:.2f} %)\n",
            r.filling * 1e6, prostate::probe_name(r.probe), r.steps, r.dt, r.wall_time,
            r.real_time_factor, r.cpu_real_time_factor, r.stepping_real_time_factor,
            r.added_mass_pct);
      }
      std::cout << fmt::format("real time: at least {:.2f}x ({}/real_time/*/report.json)\n",
                               study.real_time_factor, s.output);
    }
    const std::string json = prostate::json(study);
    write_file_atomically(std::filesystem::path(s.output) / "prostate.json",
                          [&](std::ostream& f) { f << json; });
    if (!s.json_file.empty())
      write_file_atomically(s.json_file, [&](std::ostream& f) { f << json; });
    if (!s.no_pictures) make_pictures("prostate_pictures.sh", s.output, s.quiet);
    if (!s.quiet) std::cout << fmt::format("results in {}/\n", s.output);
    return 0;
  } catch (const SceneError& e) {
    for (const auto& d : e.diagnostics()) std::cerr << "error: " << d.str() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

Command add_prostate_command(CLI::App& parent) {
  auto settings = std::make_shared<Settings>();
  Settings& s = *settings;
  prostate::Options& o = s.study;
  CLI::App* app = parent.add_subcommand(
      "prostate",
      "the prostate study: an endorectal probe pushes the prostate, bladder empty to full");
  app->add_option("--fillings", s.fillings_ml, "bladder fillings (mL)")
      ->delimiter(',')
      ->check(CLI::Range(5.0, 1000.0))
      ->capture_default_str();
  app->add_option("--probe", s.probe, "the paper's cylinder pressure, a rigid probe, or both")
      ->check(CLI::IsMember({"pressure", "rigid", "both"}))
      ->capture_default_str();
  app->add_option("--force", s.force, fmt::format("pressure probe force (N) [{}]", o.probe_force))
      ->check(CLI::Range(1e-3, 100.0));
  app->add_option("--lift", s.lift_mm,
                  fmt::format("rigid probe rise after contact (mm) [{}]", o.probe_lift * 1e3))
      ->check(CLI::Range(0.01, 20.0));
  app->add_option("--prostate-model", s.model, "shape memory (the paper) or finite elements")
      ->check(CLI::IsMember({"lsm", "fem"}))
      ->capture_default_str();
  app->add_option("--stiffness", o.prostate_stiffness, "prostate shape-memory stiffness K (N/m)")
      ->check(CLI::Range(1e-3, 1e6))
      ->capture_default_str();
  app->add_option("--young", s.young_kpa,
                  fmt::format("prostate Young's modulus, fem (kPa) [{}]", o.prostate_young * 1e-3))
      ->check(CLI::Range(0.1, 1e4));
  app->add_option("--poisson", o.prostate_poisson, "prostate Poisson ratio, fem")
      ->check(CLI::Range(0.0, 0.4999))
      ->capture_default_str();
  app->add_option("--bladder-stiffness", o.bladder_stiffness, "bladder wall shape-memory K (N/m)")
      ->check(CLI::Range(1e-3, 1e6))
      ->capture_default_str();
  app->add_option("--bladder-subdivisions", s.bladder_subdivisions,
                  fmt::format("bladder mesh: icosahedron subdivisions, 10 4^n + 2 nodes [{}]",
                              o.bladder_subdivisions))
      ->check(CLI::Range(1, 5));
  app->add_option("--support", s.support,
                  "what holds the prostate: its lateral sides, or only the bladder it hangs "
                  "from (the paper's: the bladder's top node fixed, the organs in contact)")
      ->check(CLI::IsMember({"lateral", "bladder"}))
      ->capture_default_str();
  app->add_option("--support-stiffness", o.support_stiffness,
                  "--support bladder: the lateral nodes on springs of this stiffness (N/m per "
                  "node; 0: none)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  app->add_option("--stitch-radius", s.stitch_radius_mm,
                  fmt::format("--neck prostate: the prostate's base nodes this close to its axis "
                              "are stitched to the bladder (mm) [{}]",
                              o.stitch_radius * 1e3))
      ->check(CLI::Range(1.0, 20.0));
  app->add_option("--neck", s.neck,
                  "which organ's nodes choose the neck stitches (the coarser one at the neck) "
                  "[prostate]")
      ->check(CLI::IsMember({"bladder", "prostate"}));
  app->add_option("--dt-safety", o.dt_safety,
                  "dynamic scenes: share of the stability limit taken as dt")
      ->check(CLI::Range(0.01, 1.0))
      ->capture_default_str();
  app->add_option("--dt-estimate", s.dt_estimate,
                  "dynamic scenes: the stability limit dt_safety takes its share of "
                  "(simulation.dt_estimate) [power]")
      ->check(CLI::IsMember(scene_words<DtEstimate>()));
  app->add_option("--mass-scaling", s.mass_scaling_us,
                  fmt::format("dynamic scenes: mass scaling to this stability limit (us; 0: none) "
                              "[{}]",
                              o.mass_scaling_dt * 1e6))
      ->check(CLI::Range(0.0, 1e6));
  app->add_option("--hexahedra", o.prostate_hexahedra, "prostate hexahedra per axis (even)")
      ->check(CLI::Range(2, 40))
      ->capture_default_str();
  app->add_option("--static-solver", s.static_solver,
                  "equilibria by relaxation (--relaxation) or by the implicit static solver "
                  "(simulation.solver)")
      ->check(CLI::IsMember({"relaxation", "implicit"}))
      ->capture_default_str();
  app->add_option("--relaxation", s.relaxation,
                  "--static-solver relaxation: FIRE, or kinetic damping (restarts at energy "
                  "peaks; simulation.relaxation)")
      ->check(CLI::IsMember({"fire", "kinetic"}))
      ->capture_default_str();
  app->add_option("--tolerance", o.tolerance, "equilibrium: largest residual nodal force (N)")
      ->check(CLI::Range(1e-12, 1e-2))
      ->capture_default_str();
  app->add_option("--contact-tolerance", o.contact_tolerance,
                  "equilibrium with the rigid probe or --support bladder: largest residual "
                  "nodal force (N)")
      ->check(CLI::Range(1e-12, 1e-2))
      ->capture_default_str();
  app->add_option("-o,--output", s.output, "output directory")->capture_default_str();
  app->add_option("--json", s.json_file, "also write the results as JSON to this file");
  app->add_option("--scenes", s.scenes,
                  "only write the study's scenes, in dynamics, to this directory (for phymul run)");
  app->add_flag("--coarse-bladder", s.coarse,
                "the bladder mesh that runs in real time: 162 nodes, neck chosen by the "
                "bladder, mass-scaled prostate corners; the options above still apply");
  app->add_flag("--no-real-time", s.no_realtime, "skip the real-time run");
  app->add_flag("--no-pictures", s.no_pictures, "skip the PNG pictures and plot");
  app->add_flag("-q,--quiet", s.quiet, "only the table");
  return {app, [settings] { return run(*settings); }};
}

}  // namespace phymul::cli
