// Compiling the scene's interactions (pressures, obstacles, contacts, volume schedules)
// into the model, after its objects exist.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "phymul/model.hpp"

namespace phymul {

// Resolves a node selector of an object to sorted global node ids; reports its own problems
// (unknown object, empty selection) and returns {} then.
using SelectNodes = std::function<std::vector<int>(const std::string&, const NodeSelector&)>;

void compile_interactions(const Scene& scene, Model& model, std::vector<Diagnostic>& problems,
                          const SelectNodes& select);

}  // namespace phymul
