// Volume constraints on surfaces sharing nodes, projected together (DESIGN 2.2): all the
// multipliers of one projection solved at once instead of Gauss-Seidel sweeps.
#pragma once

#include <span>
#include <vector>

#include "model/workspace.hpp"
#include "phymul/model.hpp"

namespace phymul {

// Moves the nodes by x + sum_j lambda_j w dV_j/dx (the gradients at the start, as the single
// surface's projection) with the lambdas that put every volume at its target at load_time,
// to 1e-13 relative or round-off. Returns false, having moved nothing or moved towards the
// targets, when it cannot: more than kMaxJointVolumes constraints, directions not sized by
// allocate_data, a surface that cannot change its volume, dependent gradients or no convergence.
// The caller's Gauss-Seidel sweeps then finish (and report a stuck surface).
bool project_coupled_volumes(const Model& model, const Controls& controls, Workspace& work,
                             std::span<Vec3> x, double load_time, std::span<Vec3> grad);

// Takes out of v every volume's rate at once: solves (G W G^T) mu = G v and sets
// v -= W G^T mu, after which every dV_k/dt is zero to round-off. Returns false (v untouched)
// where project_coupled_volumes would.
bool project_coupled_volume_velocities(const Model& model, Workspace& work, std::span<const Vec3> x,
                                       std::span<Vec3> v, std::span<Vec3> grad);

// The same with the nodes in `held` kept on their obstacles (each push, the way the shape
// pushes): their inverse masses lose the push direction (W' = W - W p p^T W / p.W p), so the
// volumes' rates and the held nodes' velocities along their pushes both end where they were
// to round-off: in one solve, the limit of alternating the contact's velocity stage with
// project_coupled_volume_velocities. A held node the obstacle would pull is released (and
// removed from `held`). Adds each held node's m dv to impulse[touching[node]]. Returns false
// (v untouched) without the linearisation at x kept, or after 4 passes of releases.
bool project_coupled_volume_velocities_held(const Model& model, Workspace& work,
                                            std::span<const Vec3> x, std::span<Vec3> v,
                                            std::vector<ObstacleContact>& held,
                                            std::span<const int> touching, std::span<Vec3> impulse);

// The position projection the same way, after the contact stage moved the held nodes back
// onto their obstacles: chord steps along the directions and from the factor the last
// linearisation kept (positions a small move away), the held nodes' push parts taken out, so
// they stay on a plane exactly and on a curved surface to second order in their slide. Adds
// each held node's m dx / dt to impulse[touching[node]]. False (x untouched) without a kept
// linearisation or after 4 passes of releases.
bool reproject_coupled_volumes_held(const Model& model, const Controls& controls, Workspace& work,
                                    std::span<Vec3> x, double load_time,
                                    std::vector<ObstacleContact>& held,
                                    std::span<const int> touching, std::span<Vec3> impulse,
                                    double dt);

// Takes out of the residual r what the volumes' pressures balance together: the
// least-squares multipliers p of the gradients' free parts F against r, (F F^T) p = F r,
// removed along those free parts (on_free_axes) or the whole gradients (support reactions).
// Returns false (r untouched) where project_coupled_volumes would.
// contact: nodes against an obstacle with its normal there (on_free_axes only).
bool remove_coupled_volume_pressures(const Model& model, Workspace& work, std::span<const Vec3> x,
                                     std::span<Vec3> r, std::span<Vec3> grad, bool on_free_axes,
                                     std::span<const ObstacleContact> contact = {});

}  // namespace phymul
