// The pieces of a step the static relaxation shares (step.cpp).
#pragma once

#include <span>
#include <vector>

#include "phymul/simulation.hpp"

namespace phymul {

// Throws std::invalid_argument: the model was changed after finalize (its settings, say).
[[noreturn]] void throw_not_finalized();

// One velocity Verlet or Newton-Cotes step of h (s) towards load_time; no stability check.
void step_verlet(const Model& model, Data& data, double h, double load_time);
void step_newton_cotes(const Model& model, Data& data, double h, double load_time);
// The stability checks after a step from (time, previous_load): when they fail, data goes back
// to before the step, then InstabilityError is thrown.
void checked_step(const Model& model, Data& data, double time, double previous_load);

// a = W f - c v on the free axes, tangent to the volume constraints unless volume_scratch
// (their gradients, node count) is empty, doubled groups shared.
void accelerations(const Model& model, Data& data, std::vector<Vec3>& a,
                   std::span<Vec3> volume_scratch);

}  // namespace phymul
