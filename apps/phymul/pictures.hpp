// The study commands' pictures: a script of scripts/ run on their output directory.
#pragma once

#include <fmt/format.h>

#include <cstdlib>
#include <iostream>
#include <string>

#include "phymul/installation.hpp"

namespace phymul::cli {

// Pictures need Debian's Python with matplotlib and VTK (make demo installs them): their
// absence costs the PNGs, never the numbers, so a failure is a warning.
inline void make_pictures(const std::string& script_name, const std::string& dir, bool quiet) {
  std::string script;
  try {
    script = (share_directory() / "scripts" / script_name).string();
  } catch (const std::exception& e) {
    std::cerr << "warning: the pictures were not made: " << e.what() << '\n';
    return;
  }
  const int rc =
      std::system(fmt::format("'{}' '{}' {}", script, dir, quiet ? ">/dev/null 2>&1" : "").c_str());
  if (rc != 0)
    std::cerr << fmt::format(
        "warning: the pictures were not made ({} failed; run `make demo` once to install "
        "python3-matplotlib, python3-vtk9 and xvfb)\n",
        script);
}

}  // namespace phymul::cli
