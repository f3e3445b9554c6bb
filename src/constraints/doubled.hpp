// Doubled nodes (paper, Fig. 1b): nodes of two components held at one position and one
// velocity whatever the forces on them. A group behaves as one particle of the summed
// mass under the summed force: accelerations, positions and velocities are replaced by
// their mass-weighted means (per axis; a held axis holds the whole group).
#pragma once

#include <span>
#include <vector>

#include "phymul/model.hpp"

namespace phymul {

// Mass-weighted mean over each group, per axis, written to every member: for positions,
// velocities and accelerations alike. On an axis that holds the group the value of the
// held member is taken (a prescribed displacement wins).
void project_doubled(const Model& model, std::span<Vec3> values);

// The residual of a group is the sum of its members' residuals: gathered on the first
// member, zero on the others.
void gather_doubled(const Model& model, std::span<Vec3> residual);

}  // namespace phymul
