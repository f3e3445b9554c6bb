// Contact pairs in the implicit step's global solve: each surface node of a pair inside, on,
// or (held by the last solve) near the other side's surface is a row of the solve,
// n . (dx_p - sum_j b_j dx_j) = -gap over the node and the other side's closest triangle, as a
// node on an obstacle is; the pair forces are the residual's least-squares fit with the
// volumes' pressures (a contact only pushes). The fixed point is the equilibrium with the
// frictionless contact forces, which Data::pair_contacts then holds.
#pragma once

#include "model/implicit_system.hpp"
#include "phymul/data.hpp"
#include "phymul/model.hpp"

namespace phymul {

// The faces around each node of every pair's surfaces and room for the rows (allocates).
void prepare_pair_rows(const Model& model, ImplicitSystem& s);

// At a step's start: the rows the last step ended pressing (Data::pair_contacts, which a
// checkpoint keeps) stay rows, on the surface or not, until a solve releases them.
void hold_pair_contacts(const Data& d, ImplicitSystem& s);

// Every pair's rows at d.x into s.pair_rows. Throws std::runtime_error when there are more
// than the solve takes.
void find_pair_contacts(const Model& model, Data& d, ImplicitSystem& s);

// The volumes' pressures (into pressure) and the touching rows' forces (s.pair_force) that
// fit the residual best, by least squares with each force >= 0. gg, gr: the volumes' part of
// the normal equations, as the volume-only fit has it (the obstacles' pushes left out).
void fit_pressures_and_pair_forces(const Model& model, ImplicitSystem& s, const double* gg,
                                   const double* gr, double* pressure);

// Takes the fitted pair forces out of the residual, appends every row to s.active with the
// residual's push along it before, and records the forces (Data::pair_contacts, with an
// impulse of force times d.dt, as the static residual reads them; Data::pair_contact_force).
void take_out_pair_forces(Data& d, ImplicitSystem& s);

}  // namespace phymul
