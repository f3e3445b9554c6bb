// What the implicit route (simulation: {mode: static, solver: newton}) cannot take, found in
// the scene before compiling.
#include <fmt/format.h>

#include <string>
#include <vector>

#include "model/compile_checks.hpp"

namespace phymul {
namespace {

bool uses_newton(const SimulationSpec& s) {
  return s.mode == SolveMode::static_equilibrium && s.solver == StaticSolver::newton;
}

// Where `solver: newton` was written, for messages that point at it.
std::string newton_at(const SimulationSpec& s) {
  return s.solver_loc.line > 0 ? fmt::format(" (line {})", s.solver_loc.line) : "";
}

void check_objects(const Scene& scene, std::vector<Diagnostic>& problems) {
  const std::string at = newton_at(scene.simulation);
  for (const ObjectSpec& o : scene.objects) {
    if (o.type != ObjectType::elastic) {
      problems.push_back(
          {o.loc, fmt::format("object '{}' is {}: 'solver: newton'{} takes elastic objects with "
                              "'material: {{model: fem}}' only; use 'solver: relaxation'",
                              o.name, o.type == ObjectType::rigid ? "rigid" : "active", at)});
      continue;
    }
    if (o.material.model != ElasticModel::fem)
      problems.push_back(
          {o.material.loc,
           fmt::format("object '{}' has a shape-memory material: 'solver: newton'{} takes "
                       "'model: fem' materials only (young, poisson, law); use 'solver: "
                       "relaxation' for shape memory",
                       o.name, at)});
    if (o.volume_constraint)
      problems.push_back(
          {o.loc, fmt::format("object '{}': 'volume_constraint' is not supported by 'solver: "
                              "newton'{}; give the fem material a Poisson ratio near 0.5 "
                              "instead (hexahedra do not lock), or use 'solver: relaxation'",
                              o.name, at)});
  }
}

template <class Spec>
void refuse_all(const std::vector<Spec>& specs, const char* what, const std::string& at,
                std::vector<Diagnostic>& problems) {
  for (const Spec& s : specs)
    problems.push_back(
        {s.loc, fmt::format("{} are not supported by 'solver: newton'{}: it takes 'force' "
                            "loads, 'fixed' and 'displacement' constraints, stitches and "
                            "gravity; use 'solver: relaxation'",
                            what, at)});
}

}  // namespace

void check_newton_scene(const Scene& scene, std::vector<Diagnostic>& problems) {
  const bool newton = uses_newton(scene.simulation);
  for (const ObjectSpec& o : scene.objects)
    if (!newton && o.material.model == ElasticModel::fem && o.material.law == fem::Law::linear)
      problems.push_back(
          {o.material.law_loc.line > 0 ? o.material.law_loc : o.material.loc,
           fmt::format("object '{}': 'law: linear' needs the implicit solver (simulation: "
                       "{{mode: static, solver: newton}}); the explicit finite elements (TLED) "
                       "are Neo-Hookean only",
                       o.name)});
  for (const ObjectSpec& o : scene.objects)
    if (!newton && o.material.model == ElasticModel::fem &&
        o.material.hexa == fem::HexaElement::incompatible_modes)
      problems.push_back(
          {o.material.hexa_loc.line > 0 ? o.material.hexa_loc : o.material.loc,
           fmt::format("object '{}': 'hexa: incompatible-modes' needs the implicit solver "
                       "(simulation: {{mode: static, solver: newton}}); the explicit finite "
                       "elements (TLED) use one-point hexahedra with hourglass control",
                       o.name)});
  if (!newton) return;
  check_objects(scene, problems);
  const std::string at = newton_at(scene.simulation);
  refuse_all(scene.pressures, "pressure loads", at, problems);
  refuse_all(scene.obstacles, "obstacles", at, problems);
  refuse_all(scene.contacts, "contacts", at, problems);
  refuse_all(scene.doubled, "doubled nodes", at, problems);
  for (const ConstraintSpec& c : scene.constraints)
    if (c.kind == ConstraintSpec::Kind::spring)
      problems.push_back({c.loc, fmt::format("'spring' constraints are not supported by "
                                             "'solver: newton'{}; use 'solver: relaxation'",
                                             at)});
}

}  // namespace phymul
