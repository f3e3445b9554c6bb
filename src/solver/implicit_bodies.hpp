// Free rigid bodies in the implicit step (solver/implicit_step.cpp): each body's unknowns are
// its centre's motion and a turn, a rotation vector in its principal frame, so that its node
// at offset o moves by dx = move + R (turn x o) and its inertia's block in the iteration
// matrix is the principal inertia, exact at any orientation (solver/implicit_matrix.hpp).
// Driven bodies take their pose at the step's load time and hold their nodes.
#pragma once

#include <Eigen/Core>
#include <array>
#include <span>

#include "model/implicit_system.hpp"
#include "phymul/data.hpp"

namespace phymul {

// Adds the forces on each free body's nodes into its unknowns: the force on its motion, the
// moment about its centre, in its frame, on its turn.
void gather_bodies(const Model& model, const Data& d, const ImplicitSystem& s,
                   std::span<const Vec3> field, std::array<Eigen::VectorXd, 3>& out);

// Backward Euler's inertia of the free bodies into s.residual: p0 / h - (1/h + c) M dx / h on
// the motion, L0 / h - (1/h + c) I(q) theta / h on the turn (theta the rotation vector from
// the step's start; the step's end angular momentum is I(q) theta / h, as end_bodies sets it).
void add_body_inertia(const Model& model, const Data& d, ImplicitSystem& s, double h);

// The largest squared residual of a free body: its force, and its moment over its size (N^2).
double largest_body_residual2(const Model& model, const ImplicitSystem& s);

// Keeps each body's state at the step's start, then its first guess: the free bodies drift
// with their momenta, the driven ones take their pose at load_time.
void start_bodies(const Model& model, Data& d, ImplicitSystem& s, double h, double load_time);

// The free bodies moved by alpha times their correction, their nodes with them.
void move_bodies(const Model& model, Data& d, const ImplicitSystem& s, double alpha);

// The free bodies' momenta at the step's end (the mean velocities over the step), their
// nodes' velocities with them.
void end_bodies(const Model& model, Data& d, const ImplicitSystem& s, double h);

}  // namespace phymul
