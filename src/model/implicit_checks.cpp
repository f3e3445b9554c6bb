// What the implicit static solver cannot take (needles, friction), found in the scene before
// compiling: one diagnostic each, at the field.
#include <fmt/format.h>

#include <string>
#include <vector>

#include "model/compile_checks.hpp"

namespace phymul {
namespace {

// Where `integrator: implicit` was written, for messages that point at it.
std::string implicit_at(const SimulationSpec& s) {
  return s.integrator_loc.line > 0 ? fmt::format(" (line {})", s.integrator_loc.line) : "";
}

// The same for `solver: implicit` in static mode.
std::string implicit_static_at(const SimulationSpec& s) {
  return s.solver_loc.line > 0
             ? fmt::format(" (the implicit static solver, line {})", s.solver_loc.line)
             : "";
}

constexpr const char* kTakes =
    "it takes elastic shape-memory, finite-element, active and rigid objects with gravity, "
    "'force' loads, pressures, 'fixed', 'displacement' and 'spring' constraints, stitches, "
    "doubled nodes, volume constraints, obstacles and contacts, and in dynamics friction and "
    "needles; use 'solver: relaxation'";

template <class Spec>
void refuse_all(const std::vector<Spec>& specs, const char* what, const std::string& at,
                std::vector<Diagnostic>& problems) {
  for (const Spec& s : specs)
    problems.push_back(
        {s.loc, fmt::format("{} are not supported by 'solver: implicit'{}: {}", what, at, kTakes)});
}

}  // namespace

void check_implicit_scene(const Scene& scene, std::vector<Diagnostic>& problems) {
  const SimulationSpec& s = scene.simulation;
  const bool statics = s.mode == SolveMode::static_equilibrium;
  if (statics ? s.solver != StaticSolver::implicit : s.integrator != Integrator::implicit) return;
  const std::string at = statics ? implicit_static_at(s) : implicit_at(s);
  // A static equilibrium with friction depends on the path to it, which the static solver's
  // steps (1000 dt from rest) do not follow: there the sticking and sliding nodes cycle.
  for (size_t k = 0; k < scene.obstacles.size() && statics; ++k)
    if (const ObstacleSpec& o = scene.obstacles[k]; o.friction > 0.0)
      problems.push_back(
          {o.loc,
           fmt::format("obstacle '{}' has friction {:g}, not supported by 'solver: "
                       "implicit'{}: use 'solver: relaxation' (friction is taken by "
                       "'integrator: implicit' in dynamics)",
                       o.name.empty() ? fmt::format("obstacle{}", k) : o.name, o.friction, at)});
  // Needles are inserted along a path (a depth schedule), which no static solve follows.
  if (statics) refuse_all(scene.needles, "needles", at, problems);
}

}  // namespace phymul
