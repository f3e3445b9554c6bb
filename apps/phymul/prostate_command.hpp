// `phymul prostate`: the paper's prostate, bladder and endorectal probe study.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace phymul::cli {

// Registers the subcommand; the returned callable runs it (exit code).
struct ProstateCommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};
ProstateCommand add_prostate_command(CLI::App& parent);

}  // namespace phymul::cli
