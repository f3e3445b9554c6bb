// Obstacles in the implicit step's global solve (their friction: implicit_friction.hpp): each
// node an obstacle pushes is put on its surface to first order (push . dx = -gap) by the same
// Schur complement that keeps the volumes, so the iteration's fixed point is the equilibrium with
// the contact reactions. (Projecting after an unconstrained solve instead has fixed points off
// equilibrium: P couples a held node to its neighbours.)
#pragma once

#include <span>

#include "model/implicit_system.hpp"
#include "phymul/model.hpp"

namespace phymul {

// Sizes the column cache and the Schur complement's storage for the model's obstacles and
// contact pairs, after the factors are made (allocates; nothing without either).
void prepare_implicit_contacts(const Model& model, ImplicitSystem& s);

// The contact pairs' surface nodes, both sides, all pairs: the most pair rows at once.
size_t pair_node_count(const Model& model);

// A row's g . v over its nodes' free axes, v given per axis over the unknowns.
double along(const ImplicitSystem& s, const ImplicitSystem::Contact& c,
             const std::array<Eigen::VectorXd, 3>& v);

// S z = rhs in place (S row-major n x n, symmetric positive semi-definite) by Cholesky; a
// row dependent on the earlier ones (a pivot at round-off) gets z = 0.
void solve_dense(double* S, double* rhs, int n);

// The correction P^-1 (r - G^T mu) with G the volumes' gradients and the contact rows
// (s.active), a row held unless both its multiplier (mu > 0: a tensile reaction) and its
// residual let it go: s.correction and s.solved_gradient hold P^-1 r and P^-1 g on
// entry. volume_rate: g . P^-1 r minus each volume's gap to its target. Throws
// std::runtime_error when more rows or nodes touch than the caches hold.
void constrain_to_contacts(const Model& model, ImplicitSystem& s,
                           std::span<const double> volume_rate);

}  // namespace phymul
