// `phymul mesh`: a closed surface file (STL, OBJ, PLY) filled with tetrahedra, written as .vtu.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace phymul::cli {

// Registers the subcommand; the returned callable runs it (exit code).
struct MeshCommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};
MeshCommand add_mesh_command(CLI::App& parent);

}  // namespace phymul::cli
