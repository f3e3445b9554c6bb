// Backward-Euler steps by local/global iterations (integrator: implicit; implicit_step.cpp).
#pragma once

#include "phymul/data.hpp"
#include "phymul/model.hpp"

namespace phymul {

// One backward-Euler step of h (s) towards load_time: iterations of the local step (the
// forces, every node's rotation fitted) and the global step (one solve with the matrix
// factorised for h, kept in the workspace) until the largest residual nodal force is below
// settings.implicit_tolerance or after settings.implicit_iterations solves; then v = (x -
// x0) / h; the iterations Anderson-accelerated where the model has no obstacle, contact pair
// or rigid body (implicit_anderson.hpp). Obstacles (Coulomb friction included) and contact
// pairs are rows of each solve, their forces in Data::contact_force, Data::pair_contact_force
// and Data::pair_contacts. Throws std::invalid_argument for what it does not support (finite
// elements, contact pairs with a rigid side; in the static solver's steps, friction).
// Allocates only when it factorises (the first step, a new h).
void step_implicit(const Model& model, Data& data, double h, double load_time);
// The same with its own cap on the solves and tolerance (N): the implicit static solver's.
void step_implicit(const Model& model, Data& data, double h, double load_time, int iterations,
                   double tolerance);

// The last implicit step's largest residual nodal force (N) and global solves.
double implicit_residual_force(const Data& data);
int implicit_iterations(const Data& data);

}  // namespace phymul
