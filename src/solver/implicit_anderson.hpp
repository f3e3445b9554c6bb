// Anderson acceleration of the implicit step's local/global iterations (Walker and Ni 2011;
// for projective dynamics, Peng et al. 2018): the next iterate mixes the last few iterations'
// images so as to cancel their fixed-point residuals in the least-squares sense. The history
// (Data::anderson) goes on from one step to the next: consecutive steps' iterations differ by
// their inertial terms, constant in x, and share the differences that it keeps, so a step's
// first solve already mixes.
#pragma once

#include <span>

#include "model/implicit_system.hpp"
#include "phymul/data.hpp"
#include "phymul/model.hpp"

namespace phymul {

// Sizes the iteration's buffers for the model's steps h (allocates), empty where the
// acceleration does not apply (anderson_applies; then Data::anderson is empty too), and
// voids a history taken for another h.
void prepare_anderson(const Model& model, ImplicitSystem& s, AndersonHistory& history, double h);

// Forgets the history: an iteration that made the residual grow, or one that changed the
// iterations' map (the share alpha of each correction, the held nodes, a needle's event).
void restart_anderson(ImplicitSystem& s, AndersonHistory& history);

// A new step: its first iteration has no last one to differ from; without carrying (friction,
// needles) the history starts anew.
void begin_anderson_step(ImplicitSystem& s, AndersonHistory& history);

// Takes iterate x_k (before) and its image g_k = G(x_k) (x, in place) into the history and
// replaces x by the mixed next iterate g_k - sum gamma_j dg_j, gamma minimising
// |f_k - sum gamma_j df_j| with f = g - x and df, dg the differences between consecutive
// iterations. Whether it mixed (not without a history).
bool anderson_mix(ImplicitSystem& s, AndersonHistory& history,
                  std::span<const Eigen::Vector3d> before, std::span<Eigen::Vector3d> x);

}  // namespace phymul
