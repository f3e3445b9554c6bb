// Contact with rigid analytic obstacles, enforced by projection (DESIGN 2.3 step 4).
#pragma once

#include <span>
#include <vector>

#include "phymul/data.hpp"

namespace phymul {

// Where a point stands relative to an obstacle's surface.
struct SurfaceDistance {
  double distance = 0.0;        // m, signed: negative inside the shape
  Vec3 normal = Vec3::UnitZ();  // unit, outward, at the closest surface point
};

// Signed distance and outward normal of x to the obstacle at load_time, its shape moved by
// `motion` (a Data's controls). On the medial axis (a sphere's centre, a capsule's segment)
// the normal is any direction perpendicular to the axis: every one leads to a closest point.
SurfaceDistance obstacle_distance(const RigidObstacle& obstacle, const Schedule& motion,
                                  const Vec3& x, double load_time);

// Every obstacle of the model, in order, moved by the controls' motions: moves every affected
// node that violates an obstacle (inside it; outside it when keep_inside) onto its surface,
// only along the node's free axes. A fully free node goes to the closest surface point; a
// partly held one along the normal restricted to its free axes.
void apply_contacts(const Model& model, const Controls& controls, std::span<Vec3> x,
                    double load_time);

// What one step's contact stages need and record. Buffers are the caller's, sized once
// (node count for `touching`, obstacle count for `impulse`): a step allocates nothing.
struct ContactStep {
  std::span<const Vec3> x_start;  // m, positions at the start of the step
  double start_time = 0.0;        // s, load time at the start of the step
  double dt = 0.0;                // s
  std::span<int> touching;        // per node: the obstacle that last moved it this step, or -1
  std::span<Vec3> impulse;        // N s, per obstacle: momentum it gave the body this step
  // Contact between deformable components (deformable_contact.hpp), when the model has any:
  // the contacts their stages record (Data::pair_contacts).
  std::vector<PairContact>* pair_contacts = nullptr;
  std::span<Vec3> pair_impulse;   // N s, per contact pair: momentum given to its first component
  std::span<double> pair_pushed;  // Workspace::pair_pushed: the velocity stage's scratch
  std::vector<NeedleState>* needles = nullptr;  // Data::needles, when the model has needles
};

// Position stage with Coulomb friction: projects like apply_contacts, then cancels the
// node's tangential displacement relative to the moving shape while it is within
// friction * (normal correction), else shortens it by that much. Records which nodes each
// obstacle moved and the momentum m dx / dt it gave them. Returns the largest move (m).
double apply_contacts(const Model& model, const Controls& controls, std::span<Vec3> x,
                      double load_time, ContactStep& step);

// Velocity stage (RATTLE-like) for the nodes the position stage moved: removes their
// velocity into the shape relative to its own motion, and applies Coulomb friction to the
// tangential part with the normal impulse as bound. Adds m dv to step.impulse. Returns the
// largest velocity change it made (m/s), for the stages that alternate with it.
double apply_contact_velocities(const Model& model, const Controls& controls,
                                std::span<const Vec3> x, std::span<Vec3> v, double load_time,
                                ContactStep& step);

// The nodes a position stage moved this step that lie on a frictionless obstacle's surface
// (within 1e-12 m), each with the way the shape pushes, into `held` (capacity reserved by
// allocate_data). False, `held` then meaningless, where a touching obstacle has friction.
bool on_obstacles(const Model& model, const Controls& controls, std::span<const Vec3> x,
                  double load_time, const ContactStep& step, std::vector<ObstacleContact>& held);

// The nodes a velocity stage left on a frictionless obstacle's surface, not leaving it (their
// velocity relative to the shape has no outward part above 1e-12 m/s): each with the way the
// shape pushes, into `held` (capacity reserved by allocate_data). False, `held` then
// meaningless, where a touching obstacle has friction: its tangential stage does not commute
// with the volumes' projection.
bool resting_on_obstacles(const Model& model, const Controls& controls, std::span<const Vec3> x,
                          std::span<const Vec3> v, double load_time, const ContactStep& step,
                          std::vector<ObstacleContact>& held);

}  // namespace phymul
