// Constraints satisfied by projection after the force phase (DESIGN 2.2, 2.3 step 4).
#pragma once

#include <span>

#include "model/workspace.hpp"
#include "phymul/model.hpp"

namespace phymul {

// Puts every prescribed axis exactly at rest position + displacement(load_time): fixed
// nodes get their rest coordinates bit for bit.
void apply_prescribed(const Model& model, std::span<Vec3> x, double load_time);

// Volume gradient dV/dx_i (m^2) of a closed surface, accumulated into grad (zeroed first on
// the constraint's nodes).
void volume_gradient(const VolumeConstraint& c, std::span<const Vec3> x, std::span<Vec3> grad);
// The same from the gradient the last projection kept (cache) where it was taken at x.
void volume_gradient(const VolumeConstraint& c, const VolumeCache& cache, std::span<const Vec3> x,
                     std::span<Vec3> grad);

// Moves the surface nodes along w_i dV/dx_i (w = per-axis inverse mass, 0 on held axes) by
// the root of the cubic V(x + lambda d) = target (m^3) nearest to 0. Returns lambda; throws
// std::runtime_error when no free node can change the volume. grad is scratch (node count).
// Reports |V - target| / target before the move.
double project_volume(const VolumeConstraint& c, std::span<const Vec3> inverse_mass,
                      std::span<Vec3> x, std::span<Vec3> grad, double target,
                      double* relative_error_before = nullptr);

// Every volume constraint at its target at load_time: one pass when the surfaces are
// disjoint, Gauss-Seidel sweeps until all are within round-off when they share nodes.
// work: the volume caches. start: within a step, the positions it began at; a disjoint
// surface whose velocity projection kept its gradient there moves along that gradient (SHAKE's
// direction, which saves a gradient pass) rather than along the one at x.
// controls: the targets (Controls::target_volume).
void project_volumes(const Model& model, const Controls& controls, Workspace& work,
                     std::span<Vec3> x, double load_time, std::span<Vec3> scratch,
                     std::span<const Vec3> start = {});

// A node on an obstacle (or a contact pair) and on a kept volume's surface: the volume's
// correction moves it back into the obstacle. Runs `contact` then `volume` until `contact`
// (returning the largest change it made) changes nothing above `settled`; each round shrinks
// the change fifty- to a hundredfold, at most 20 rounds. The caller ran both once already.
// Where `can_hold`, the first round's volume stage is `hold` instead, the rounds' limit in
// one solve (coupled_volume.hpp; false where it could not, and `volume` runs), and the rounds
// after it finish what it leaves.
template <class Contact, class Volume, class Hold>
void alternate_contact_and_volume(Contact&& contact, Volume&& volume, bool can_hold, Hold&& hold,
                                  double settled) {
  constexpr int kMostRounds = 20;
  if (can_hold && contact() > 0.0 && !hold()) volume();
  for (int round = 0; round < kMostRounds; ++round) {
    const double changed = contact();
    if (changed == 0.0) return;
    volume();
    if (changed <= settled) return;
  }
}

// All position constraints in the DESIGN's order: prescribed, rigid obstacles (contact.hpp),
// then volumes (a few Gauss-Seidel sweeps when surfaces share nodes), then doubled nodes
// (doubled.hpp). Rigid bodies place their nodes before (solver/rigid.hpp).
// controls: the obstacles' motions and the volumes' targets.
void apply_position_constraints(const Model& model, const Controls& controls, Workspace& work,
                                std::span<Vec3> x, double load_time, std::span<Vec3> scratch);
// The same within a step: contacts with friction, recording what they moved (contact.hpp).
struct ContactStep;
void apply_position_constraints(const Model& model, const Controls& controls, Workspace& work,
                                std::span<Vec3> x, double load_time, std::span<Vec3> scratch,
                                ContactStep& contact);

// Removes from the velocities their rate of change of each constrained volume, along the
// same mass-weighted direction as the position projection (RATTLE's velocity stage), so
// that the velocities are tangent to the constraint after the second half kick.
void project_volume_velocities(const Model& model, Workspace& work, std::span<const Vec3> x,
                               std::span<Vec3> v, std::span<Vec3> scratch);

}  // namespace phymul
