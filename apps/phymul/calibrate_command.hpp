// `phymul calibrate`: alpha of K = alpha * E * h per mesh type, and its check on a cantilever.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace phymul::cli {

// Registers the subcommand; the returned callable runs it (exit code).
struct CalibrateCommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};
CalibrateCommand add_calibrate_command(CLI::App& parent);

}  // namespace phymul::cli
