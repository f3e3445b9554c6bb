// Anderson acceleration of the implicit step's local/global iterations (Walker and Ni 2011;
// for projective dynamics, Peng et al. 2018): the next iterate mixes the last few iterations'
// images so as to cancel their fixed-point residuals in the least-squares sense.
#pragma once

#include <span>

#include "model/implicit_system.hpp"
#include "phymul/model.hpp"

namespace phymul {

// Sizes the history for the model's iterations (allocates), or leaves it empty where the
// acceleration does not apply: contact pairs and rigid bodies change the rows or unknowns
// from one iteration to the next in ways a mix across them would ignore (a change of the
// obstacles' held nodes restarts the history instead: implicit_step.cpp).
void prepare_anderson(const Model& model, ImplicitSystem& s);

// Forgets the history: a new step, or an iteration that made the residual grow.
void restart_anderson(ImplicitSystem& s);

// Takes iterate x_k (before) and its image g_k = G(x_k) (x, in place) into the history and
// replaces x by the mixed next iterate g_k - sum gamma_j (g_{j+1} - g_j), gamma minimising
// |f_k - sum gamma_j (f_{j+1} - f_j)| with f = g - x. Whether it mixed (not without a
// history).
bool anderson_mix(ImplicitSystem& s, std::span<const Eigen::Vector3d> before,
                  std::span<Eigen::Vector3d> x);

}  // namespace phymul
