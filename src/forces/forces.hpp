// The force phase of a step (DESIGN 2.3, step 2): every force but damping.
#pragma once

#include "phymul/model.hpp"

namespace phymul {

// State::f = gravity + applied forces at load_time + shape memory, at positions State::x.
// Also updates State::rotation and State::shape_memory_energy.
void compute_forces(const Model& model, State& state, double load_time);

}  // namespace phymul
