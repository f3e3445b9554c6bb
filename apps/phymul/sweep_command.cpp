#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include "commands.hpp"

namespace phymul::cli {
namespace {

namespace fs = std::filesystem;

// Debian's interpreter: the one the module is built for, the only one that sees Debian's
// Dask, pandas and PyYAML. PHYMUL_PYTHON overrides it.
constexpr const char* kPython = "/usr/bin/python3";

struct Settings {
  std::string sweep, output, scheduler;
  int workers = 0;  // 0: every core
  bool resume = false, quiet = false;
  int stop_after = 0;  // hidden, for tests: as if interrupted after that many samples
};

fs::path running_program() {
  std::error_code ec;
  const fs::path program = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the running program's path (/proc/self/exe)");
  return program;
}

// Where the phymul package lives: beside a build tree's program (<build>/python/phymul), or
// where `cmake --install` put it (<prefix>/lib/python3.X/dist-packages/phymul).
std::vector<fs::path> module_candidates(const fs::path& program) {
  std::vector<fs::path> candidates{program.parent_path() / "python"};
  const fs::path lib = program.parent_path().parent_path() / "lib";
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(lib, ec))
    if (entry.path().filename().string().rfind("python3", 0) == 0)
      candidates.push_back(entry.path() / "dist-packages");
  return candidates;
}

fs::path module_directory(const fs::path& program) {
  const std::vector<fs::path> candidates = module_candidates(program);
  std::string looked;
  for (const fs::path& dir : candidates) {
    std::error_code ec;
    if (fs::is_regular_file(dir / "phymul" / "sweep.py", ec)) return dir;
    looked += (looked.empty() ? "" : ", ") + dir.string();
  }
  throw std::runtime_error(fmt::format(
      "the phymul Python module is missing (looked in {}): build it (cmake --build build "
      "--target phymul_python) or install it (cmake --install build)",
      looked));
}

std::vector<std::string> python_arguments(const Settings& s, const std::string& python) {
  std::vector<std::string> args{python, "-m", "phymul", "sweep", s.sweep, "-o", s.output};
  if (!s.scheduler.empty()) args.insert(args.end(), {"--scheduler", s.scheduler});
  if (s.workers > 0) args.insert(args.end(), {"--workers", std::to_string(s.workers)});
  if (s.resume) args.emplace_back("--resume");
  if (s.quiet) args.emplace_back("--quiet");
  if (s.stop_after > 0) args.insert(args.end(), {"--stop-after", std::to_string(s.stop_after)});
  return args;
}

// Replaces this process by the Python sweep, so that its exit code, its signals (Ctrl-C,
// a batch system's SIGTERM) and its terminal are the command's own.
int run(const Settings& s) {
  try {
    const fs::path program = running_program();
    const fs::path modules = module_directory(program);
    const char* old_path = std::getenv("PYTHONPATH");
    const std::string path =
        modules.string() + (old_path && *old_path ? std::string(":") + old_path : "");
    setenv("PYTHONPATH", path.c_str(), 1);
    setenv("PHYMUL_PROGRAM", program.c_str(), 1);  // the study sweeps run this very program
    const char* python_env = std::getenv("PHYMUL_PYTHON");
    const std::string python = python_env && *python_env ? python_env : kPython;
    std::vector<std::string> args = python_arguments(s, python);
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(python.c_str(), argv.data());
    std::cerr << fmt::format(
        "error: cannot start {} ({}); phymul sweep needs Debian's Python "
        "with python3-distributed and python3-pandas (or PHYMUL_PYTHON)\n",
        python, std::strerror(errno));
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << '\n';
  }
  return 1;
}

}  // namespace

Command add_sweep_command(CLI::App& parent) {
  auto settings = std::make_shared<Settings>();
  Settings& s = *settings;
  CLI::App* app = parent.add_subcommand(
      "sweep", "run a parameter sweep (sweep file) on Dask: a local cluster or --scheduler");
  app->add_option("sweep", s.sweep, "sweep file (YAML; docs/scale-out.md)")->required();
  app->add_option("-o,--output", s.output,
                  "output directory: results.csv, samples/<id>/, summary.png")
      ->required();
  auto* scheduler = app->add_option("--scheduler", s.scheduler,
                                    "an existing Dask scheduler: tcp://HOST:PORT, or the file "
                                    "`dask scheduler --scheduler-file` wrote (default: a local "
                                    "cluster bound to 127.0.0.1)");
  app->add_option("--workers", s.workers, "local cluster: worker processes (default: every core)")
      ->check(CLI::Range(1, 4096))
      ->excludes(scheduler);
  app->add_flag("--resume", s.resume,
                "continue the sweep in the output directory: samples finished ok are kept");
  app->add_flag("-q,--quiet", s.quiet, "no progress line");
  app->add_option("--stop-after", s.stop_after)->group("");  // tests: as if interrupted there
  return {app, [settings] { return run(*settings); }};
}

}  // namespace phymul::cli
