// The program's commands beyond run, check and schema, one file each: each registers itself
// on the parent app and returns the callable that runs it (its exit code).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace phymul::cli {

struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

Command add_truthcube_command(CLI::App& parent);   // the Truth Cube validation
Command add_calibrate_command(CLI::App& parent);   // stiffness from Young's modulus
Command add_prostate_command(CLI::App& parent);    // the prostate study
Command add_sweep_command(CLI::App& parent);       // parameter sweeps (Python, Dask)
Command add_mesh_command(CLI::App& parent);        // closed surface -> tetrahedra
Command add_serve_command(CLI::App& parent);       // the live view in the browser
Command add_export_pml_command(CLI::App& parent);  // a scene as CamiTK PML and LML

}  // namespace phymul::cli
