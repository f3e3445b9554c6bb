// Pressure on boundary faces as a follower load (the paper's probe pressure).
#pragma once

#include <span>

#include "phymul/model.hpp"

namespace phymul {

// Adds to f the pressure p (Pa) on load's faces: on each face, -p * (area-weighted outward
// normal of the current triangle) / 3 on each of its nodes. Allocates nothing.
void add_pressure(const PressureLoad& load, double p, std::span<const Vec3> x, std::span<Vec3> f);

}  // namespace phymul
