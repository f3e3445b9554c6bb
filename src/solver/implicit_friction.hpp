// Coulomb friction on rigid obstacles in the implicit step. On a node the residual presses
// into a rough obstacle with a normal force N, the force that would hold it where it started
// the step (relative to the shape) is its tangential pull plus backward Euler's inertial
// spring-back from its slip. Within mu N the node sticks: the obstacle takes that force and two
// rows of the global solve along the surface's tangents bring its slip to zero. Beyond, it
// slides: the obstacle pushes mu N against that force. The iteration's fixed point is backward
// Euler with Coulomb's law on every touching node: a sticking node has not slipped and needs
// at most mu N; a sliding one slips along its pull, which mu N holds back.
#pragma once

#include "model/implicit_system.hpp"
#include "phymul/model.hpp"
#include "phymul/simulation.hpp"

namespace phymul {

// Whether any obstacle of the model has friction.
bool with_friction(const Model& model);

// Sizes the per-node friction state where an obstacle has friction (allocates; nothing
// otherwise).
void prepare_implicit_friction(const Model& model, ImplicitSystem& s);

// A step's start: each obstacle's shift over the step, from d.load_time to load_time.
void start_friction(const Model& model, const Data& d, ImplicitSystem& s, double load_time);

// On a node that the residual presses into a rough obstacle with a normal force `normal` (N),
// its normal row at `normal_row` of s.active: the friction force added to s.residual, and for
// a sticking node its two tangent rows appended to s.active. Returns the friction force (N).
Vec3 add_friction(const Model& model, const Data& d, ImplicitSystem& s, int node, const Vec3& push,
                  int obstacle, double normal, int normal_row);

}  // namespace phymul
