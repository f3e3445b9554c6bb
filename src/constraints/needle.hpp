// Needle insertion by constraints (DiMaio and Salcudean 2003; Duriez et al. 2009): the tip
// presses the surface until the tissue's puncture force, then the tissue met by the tip is
// held on the shaft through embedded track points with stick-slip friction along it
// (docs/needles.md). After the obstacles and deformable contacts, before the volumes.
#pragma once

#include <span>

#include "constraints/contact.hpp"

namespace phymul {

// The needle's tip (m) at `depth` (m) along its axis.
inline Vec3 needle_tip(const Needle& n, double depth) { return n.base + depth * n.direction; }

// The axial force (N) of the tissues on the needle, positive when they resist insertion, and
// the size of its lateral part.
inline double needle_axial_force(const Needle& n, const NeedleState& s) {
  return -s.force.dot(n.direction);
}
inline double needle_lateral_force(const Needle& n, const NeedleState& s) {
  return (s.force - s.force.dot(n.direction) * n.direction).norm();
}

// One step's needle stage: each needle at its depth at load_time (the controls'), the
// tissues pressed, punctured, tracked, released; step.needles records it (positions moved
// by the least mass-weighted change; the reaction over step.dt into NeedleState::force).
void apply_needles(const Model& model, const Controls& controls, std::span<Vec3> x,
                   double load_time, ContactStep& step);

}  // namespace phymul
