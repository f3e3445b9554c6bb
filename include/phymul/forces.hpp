// The force phase of a step (DESIGN 2.3, step 2): every force but damping.
#pragma once

#include "phymul/data.hpp"
#include "phymul/model.hpp"

namespace phymul {

// Gravity, applied forces and pressures at load_time, shape memory, fibres and explicit
// finite elements at data.x into data.f; also updates data.rotation (the shape memory's
// warm-started fits) and data.shape_memory_energy. Allocates nothing.
void compute_forces(const Model& model, Data& data, double load_time);

}  // namespace phymul
