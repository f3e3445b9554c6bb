#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "phymul/calibration.hpp"
#include "phymul/vtk.hpp"

namespace phymul::cli {
namespace {

struct Settings {
  calibration::Options options;
  std::vector<int> resolutions{4, 8};
  std::vector<std::string> types{"hexa", "tetra"};
  std::string json_file;
  bool no_volume = false, no_cantilever = false;
};

int run(Settings& s) {
  s.options.volume_constraint = !s.no_volume;
  s.options.cantilever = !s.no_cantilever;
  std::vector<CellType> types;
  for (const std::string& t : s.types)
    types.push_back(t == "tetra" ? CellType::tetra : CellType::hexa);
  try {
    const calibration::Result result = calibration::run(types, s.resolutions, s.options);
    if (!s.json_file.empty())
      write_file_atomically(s.json_file, [&](std::ostream& o) { o << calibration::json(result); });
    std::cout << calibration::table(result);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

Command add_calibrate_command(CLI::App& parent) {
  auto settings = std::make_shared<Settings>();
  Settings& s = *settings;
  CLI::App* app = parent.add_subcommand(
      "calibrate", "stiffness from Young's modulus: alpha of K = alpha E h per mesh type vs FEM");
  app->add_option("--cells", s.resolutions, "cells per 40 mm cube edge, one run each")
      ->check(CLI::Range(1, 32))
      ->capture_default_str();
  app->add_option("--type", s.types, "mesh types")
      ->check(CLI::IsMember({"hexa", "tetra"}))
      ->capture_default_str();
  app->add_option("--json", s.json_file, "also write the results as JSON to this file");
  app->add_option("--strain", s.options.strain, "calibration compression")
      ->check(CLI::Range(1e-4, 0.2))
      ->capture_default_str();
  app->add_option("--poisson-hexa", s.options.poisson_hexa, "FEM Poisson ratio on hexahedra")
      ->check(CLI::Range(0.0, 0.4999))
      ->capture_default_str();
  app->add_option("--poisson-tetra", s.options.poisson_tetra,
                  "FEM Poisson ratio on tetrahedra (linear tetrahedra lock near 0.5)")
      ->check(CLI::Range(0.0, 0.4999))
      ->capture_default_str();
  app->add_option("--beam-young", s.options.beam_young, "cantilever Young's modulus (Pa)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app->add_option("--tolerance", s.options.tolerance,
                  "shape-memory equilibrium: residual nodal force over the load's nodal force")
      ->check(CLI::Range(1e-12, 1e-2))
      ->capture_default_str();
  app->add_flag("--no-volume", s.no_volume, "no volume constraint on the shape-memory model");
  app->add_flag("--no-cantilever", s.no_cantilever, "skip the cantilever check");
  return {app, [settings] { return run(*settings); }};
}

}  // namespace phymul::cli
