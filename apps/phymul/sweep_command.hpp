// `phymul sweep`: parameter sweeps on Dask distributed, run by the Python module (phymul.sweep).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace phymul::cli {

// Registers the subcommand; the returned callable runs it (exit code).
struct SweepCommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};
SweepCommand add_sweep_command(CLI::App& parent);

}  // namespace phymul::cli
