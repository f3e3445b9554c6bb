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

// Moves the embedded point by `delta` (m) with the least mass-weighted change of its nodes
// (each by its weight times its inverse mass, held axes not at all); returns the momentum
// given (N s) over dt.
Vec3 move_point(const Model& model, const EmbeddedPoint& p, const Vec3& delta, std::span<Vec3> x,
                double dt);

// The needle stage's bookkeeping, shared with the implicit step (solver/implicit_needles.hpp).
// On the way out (depth below the last step's), points the tip has passed (their anchor ahead
// of it on the shaft) let go; a tissue with no point left heals and may be punctured again.
void release_track(NeedleState& s, double depth);
// Every `spacing` of advance, a track point at the tip in the punctured tissue it is in (the
// newest point of its tetrahedron taking the travel instead, if it has one); updates
// s.tip_tissue.
void extend_track(const Needle& n, NeedleState& s, std::span<const Vec3> x, double depth,
                  bool advancing);
// The tissue whose surface the tip presses (-1: none): the one pressed already, or, while
// advancing, the first untouched one the tip is in, its point at the tip becoming s.contact.
int pressed_tissue(const Needle& n, NeedleState& s, std::span<const Vec3> x, double depth,
                   bool advancing);

// One step's needle stage: each needle at its depth at load_time (the controls'), the
// tissues pressed, punctured, tracked, released; step.needles records it (positions moved
// by the least mass-weighted change; the reaction over step.dt into NeedleState::force).
void apply_needles(const Model& model, const Controls& controls, std::span<Vec3> x,
                   double load_time, ContactStep& step);

}  // namespace phymul
