// Active components (muscle): contractile fibres along polylines through the nodes. Each
// segment is a tension-only spring whose rest length l0 shortens to l0 (1 - a(t) ratio)
// with the activation a(t) in [0, 1]; the passive shape memory of the component stays.
// The paper names active components without their law: this is the simplest contractile
// element with an energy, E = K/2 sum max(0, l - l0 (1 - a ratio))^2, so the forces are
// equal and opposite along each segment and keep momentum.
#pragma once

#include <span>

#include "phymul/model.hpp"

namespace phymul {

// Adds the fibre forces (N) at load_time to f; returns their energy (J).
double add_fibre_forces(const FibreBundle& fibres, std::span<const Vec3> x, double load_time,
                        std::span<Vec3> f);

// The activation at t, clamped to [0, 1].
double activation_at(const FibreBundle& fibres, double t);

}  // namespace phymul
