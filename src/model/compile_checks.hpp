// Scene checks compile_scene runs before it builds anything (model/compile_scene.cpp).
#pragma once

#include <vector>

#include "phymul/scene.hpp"

namespace phymul {

// What `solver: newton` cannot take (objects that are not fem-elastic, volume constraints,
// pressures, obstacles, contacts, doubled nodes) and `law: linear` outside it: one
// diagnostic each, at the offending field, saying what is allowed.
void check_newton_scene(const Scene& scene, std::vector<Diagnostic>& problems);

// What `integrator: implicit` cannot take in dynamics (rigid and active objects, fem
// materials, obstacles, contacts): one diagnostic each, at the offending field.
void check_implicit_scene(const Scene& scene, std::vector<Diagnostic>& problems);

}  // namespace phymul
