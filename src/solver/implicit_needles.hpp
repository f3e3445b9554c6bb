// Needles in the implicit step (docs/needles.md's model with its constraints in the global
// solve): the surface point the tip presses takes three rows onto the tip; each track point two
// rows onto the shaft's axis and, while it sticks, one along it at its anchor. A sliding
// point's kinetic friction and the cut point's cutting force are loads in the residual. The
// rows are fitted with the volumes' pressures and the contact pairs' forces (implicit_pairs.hpp)
// and never let go by their sign. A step's state changes go one way: the tip presses and the
// track grows at its start; within it a point may start sliding and the surface give way.
#pragma once

#include "model/implicit_system.hpp"
#include "phymul/data.hpp"
#include "phymul/model.hpp"

namespace phymul {

// The most needle rows a solve takes at once, for the model's needles.
size_t needle_row_count(const Model& model);

// Room for each needle's sliding states (allocates; nothing without needles).
void prepare_implicit_needles(const Model& model, ImplicitSystem& s);

// At a step's start, after the first guess: each needle at its depth at load_time lets go of
// the track it withdrew from, presses a surface it entered, adds a track point at the tip;
// every point sticks.
void start_needles(const Model& model, Data& d, ImplicitSystem& s, double load_time);

// The needles' rows at d.x appended to s.pair_rows, and the sliding and cut points' loads
// added to s.residual (over the unknowns).
void add_needle_rows(const Model& model, Data& d, ImplicitSystem& s, double load_time);

// After the fit (s.pair_force): each needle's force (NeedleState::force, the tissues' on it).
// With `decide` (the iterations converged, their forces final), a pressed surface whose push
// exceeds the puncture force gives way and a sticking point whose axial force exceeds its
// friction slides for the rest of the step; s.needles_changed says whether any did.
void update_needles(const Model& model, Data& d, ImplicitSystem& s, double load_time, bool decide);

// The needles' constraints projected, as the explicit stage does (the least mass-weighted
// moves of each point's nodes, Gauss-Seidel over the points): the first guess and each solve's
// result start on them, so that a tissue at rest that the tip enters is not taken for converged.
void project_needles(const Model& model, Data& d, const ImplicitSystem& s, double load_time);

// At the step's end: sliding points stick where they went; each needle's depth is load_time's.
void end_needles(const Model& model, Data& d, const ImplicitSystem& s, double load_time);

}  // namespace phymul
