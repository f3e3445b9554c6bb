// `phymul truthcube`: the Truth Cube validation table, files and pictures.
#pragma once

#include <CLI/CLI.hpp>

namespace phymul::cli {

// Registers the subcommand; the returned callable runs it (exit code).
struct TruthcubeCommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};
TruthcubeCommand add_truthcube_command(CLI::App& parent);

}  // namespace phymul::cli
