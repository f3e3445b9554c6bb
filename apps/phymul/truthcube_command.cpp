#include <fmt/format.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "phymul/installation.hpp"
#include "phymul/scene_words.hpp"
#include "phymul/studies/truthcube.hpp"
#include "phymul/vtk.hpp"
#include "pictures.hpp"

namespace phymul::cli {
namespace {

struct Settings {
  truthcube::StudyOptions study;
  std::string data;  // default: the installed copy of the measured beads
  std::string output = "results/truthcube";
  std::string json_file;
  std::string frame = "polar";
  std::string fem_hexa = "mean-dilatation";
  std::string solver = "relaxation";
  bool no_reaction = false, no_volume = false, no_fem = false, no_pictures = false;
  bool quiet = false;
};

int run(Settings& s) {
  s.study.frame = scene_value<FrameMode>(s.frame).value_or(FrameMode::polar);
  s.study.reaction = !s.no_reaction;
  s.study.volume_constraint = !s.no_volume;
  s.study.fem = !s.no_fem;
  s.study.solver = s.solver == "implicit" ? StaticSolver::implicit : StaticSolver::relaxation;
  s.study.incompatible_modes = s.fem_hexa == "incompatible";
  try {
    if (s.data.empty())
      s.data = (share_directory() / "data" / "truthcube" / "uniaxial_positions.csv").string();
    const auto beads = truthcube::load_beads(s.data);
    const truthcube::Study study = truthcube::run_study(beads, s.study);
    truthcube::write_outputs(study, beads, s.study, s.output);
    if (!s.json_file.empty())
      write_file_atomically(s.json_file,
                            [&](std::ostream& o) { o << truthcube::json(study, s.study); });
    std::cout << truthcube::table(study, s.study);
    if (!s.no_pictures) make_pictures("truthcube_pictures.sh", s.output, s.quiet);
    if (!s.quiet) std::cout << fmt::format("results in {}/\n", s.output);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

Command add_truthcube_command(CLI::App& parent) {
  auto settings = std::make_shared<Settings>();
  Settings& s = *settings;
  CLI::App* app = parent.add_subcommand(
      "truthcube", "the Truth Cube validation: beads measured vs shape memory and FEM");
  app->add_option("--cells", s.study.cells, "hexahedra per cube edge")
      ->check(CLI::Range(2, 64))
      ->capture_default_str();
  app->add_option("--data", s.data,
                  "bead positions (CSV; default: the measured ones phymul ships, "
                  "share/phymul/data/truthcube)")
      ->check(CLI::ExistingFile);
  app->add_option("-o,--output", s.output, "output directory")->capture_default_str();
  app->add_option("--json", s.json_file, "also write the table as JSON to this file");
  app->add_option("--frame", s.frame, "shape-memory frame")
      ->check(CLI::IsMember(scene_words<FrameMode>()))
      ->capture_default_str();
  app->add_option("--solver", s.solver,
                  "shape-memory equilibria: FIRE relaxation or the implicit static solver")
      ->check(CLI::IsMember({"relaxation", "implicit"}))
      ->capture_default_str();
  app->add_flag("--no-reaction", s.no_reaction, "the paper's force on the node alone");
  app->add_flag("--no-volume", s.no_volume, "no volume constraint on the shape-memory model");
  app->add_flag("--sliding", s.study.sliding, "plates let the faces slide (default: no slip)");
  app->add_flag("--no-fem", s.no_fem, "skip the reference FEM");
  app->add_flag("--no-pictures", s.no_pictures, "skip the PNG plot and rendering");
  app->add_option("--poisson", s.study.poisson, "FEM Poisson ratio")
      ->check(CLI::Range(0.0, 0.4999))
      ->capture_default_str();
  app->add_option(
         "--fem-hexa", s.fem_hexa,
         "FEM hexahedron: mean dilatation (Q1/P0) or incompatible modes (CalculiX's C3D8I)")
      ->check(CLI::IsMember({"mean-dilatation", "incompatible"}))
      ->capture_default_str();
  app->add_option("--tolerance", s.study.tolerance,
                  "shape-memory equilibrium: largest residual force over K h")
      ->check(CLI::Range(1e-12, 1e-2))
      ->capture_default_str();
  app->add_flag("-q,--quiet", s.quiet, "only the table");
  return {app, [settings] { return run(*settings); }};
}

}  // namespace phymul::cli
