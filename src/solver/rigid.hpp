// Rigid components as 6-DoF bodies (DESIGN 2, "rigid"): the forces on their nodes give a
// force and a torque; the pose is integrated by a symplectic splitting (kick, drift, kick)
// whose free rotation is the exact-per-axis splitting of Dullweber, Leimkuhler and
// McLachlan (1997): it keeps the angular momentum exactly and the energy to O(h^2) without
// drift, so an asymmetric body tumbles about its principal axes as it should.
#pragma once

#include "phymul/data.hpp"

namespace phymul {

// Net force (N) and torque about the centre (N m) of the forces Data::f on the body's
// nodes, less (when damped) the mass-proportional damping of their velocities.
void rigid_load(const Model& model, const Data& state, int body, Vec3& force, Vec3& torque,
                bool damped);

// Half kick: momenta += h/2 (force, torque) for every free body, then the node velocities
// from the body velocities.
void kick_rigid_bodies(const Model& model, Data& state, double h);

// Drift: free bodies move by h with their momenta (free rotation by the splitting); driven
// ones take their pose at load_time. Node positions are set from the poses.
void drift_rigid_bodies(const Model& model, Data& state, double h, double load_time);

// Node positions (and velocities) from the bodies' poses and momenta.
void place_rigid_nodes(const Model& model, Data& state);

// Zero momenta (static relaxation restarts from rest).
void stop_rigid_bodies(Data& state);

// Largest out-of-balance of the free bodies: |force| and |torque| / size (N).
double rigid_residual(const Model& model, const Data& state);

// Free rotation of a body with principal moments `inertia` and world angular momentum L for
// a time h: the symmetric splitting over the three principal axes.
void rotate_free_body(const Vec3& inertia, const Vec3& L, double h, Eigen::Quaterniond& q);

}  // namespace phymul
