// Example scenes compiled for the solvers' comparisons.
#pragma once

#include <string>

#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "support/process.hpp"

namespace phymul::testing {

// examples/`name` in this mode, integrator and static solver, every tolerance at 1e-10 N and
// room to reach it (2e6 relaxation iterations, 2000 solves an implicit step).
inline Model compile_example(const std::string& name, SolveMode mode, Integrator integrator,
                             StaticSolver solver) {
  Scene s = load_scene(source_dir() / "examples" / name);
  s.simulation.mode = mode;
  s.simulation.integrator = integrator;
  s.simulation.solver = solver;
  s.simulation.tolerance = 1e-10;
  s.simulation.max_iterations = 2000000;
  s.simulation.implicit_iterations = 2000;
  s.simulation.implicit_tolerance = 1e-10;
  return compile_scene(s);
}

}  // namespace phymul::testing
