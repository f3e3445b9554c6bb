#include "constraints/contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "constraints/deformable_contact.hpp"

namespace phymul {
namespace {

using Shape = RigidObstacle::Shape;

// A unit vector perpendicular to axis (the normal of a point on a medial axis is arbitrary).
Vec3 any_perpendicular(const Vec3& axis) {
  const Vec3 trial = std::abs(axis.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  return axis.cross(trial).normalized();
}

// Distance to a round shape: the ball of `radius` around the point `core` of its core.
SurfaceDistance around(const Vec3& x, const Vec3& core, double radius, const Vec3& axis) {
  const Vec3 r = x - core;
  const double d = r.norm();
  return {d - radius, d > 0.0 ? Vec3(r / d) : any_perpendicular(axis)};
}

// Closest point of the core segment (or, with an infinite base, ray) to x.
Vec3 core_point(const RigidObstacle& o, const Vec3& base, const Vec3& x) {
  const double lowest = o.shape == Shape::capsule ? 0.0 : -std::numeric_limits<double>::infinity();
  const double t = std::clamp((x - base).dot(o.axis), lowest, o.length);
  return base + t * o.axis;
}

bool violates(const RigidObstacle& o, double distance) {
  return o.keep_inside ? distance > 0.0 : distance < 0.0;
}

// Where the shape's reference point is at a load time: evaluated once per obstacle and
// stage, not per node (the motion is a schedule to interpolate).
Vec3 shape_base(const RigidObstacle& o, const Schedule& motion, double load_time) {
  return o.point + motion.at(load_time);
}

// obstacle_distance with the shape's base point already placed.
SurfaceDistance distance_from(const RigidObstacle& o, const Vec3& base, const Vec3& x) {
  switch (o.shape) {
    case Shape::plane:
      return {(x - base).dot(o.axis), o.axis};
    case Shape::sphere:
      return around(x, base, o.radius, o.axis);
    case Shape::capsule:
    case Shape::probe:
      return around(x, core_point(o, base, x), o.radius, o.axis);
  }
  return {};
}

bool violates_at(const RigidObstacle& o, const Vec3& x, const Vec3& base) {
  return violates(o, distance_from(o, base, x).distance);
}

// Moves one node onto the surface along its free axes P. A free node goes straight to the
// closest point (exact for every shape). A partly held one moves along P n0 (n0: the normal
// where it starts): Newton steps until it is out, then bisection back to the surface, since
// on a curved surface a linearised step may overshoot far past it.
void project_node(const RigidObstacle& o, const Vec3& free_axes, Vec3& x, const Vec3& base) {
  const SurfaceDistance s = distance_from(o, base, x);
  if (!violates(o, s.distance)) return;
  if (free_axes == Vec3::Ones()) {
    x -= s.distance * s.normal;
    return;
  }
  const Vec3 direction = s.normal.cwiseProduct(free_axes);
  if (s.normal.dot(direction) < 1e-12) return;  // the normal lies on held axes: cannot move
  double inside = 0.0, outside = 0.0;           // step lengths along direction
  for (int pass = 0; pass < 8 && outside == 0.0; ++pass) {
    const SurfaceDistance at = distance_from(o, base, x + inside * direction);
    const double rate = at.normal.dot(direction);
    const double next = rate > 0.0 ? inside - at.distance / rate : 2.0 * inside;
    if (violates_at(o, x + next * direction, base))
      inside = next;
    else
      outside = next;
  }
  if (outside == 0.0) return;  // no way out along the free axes: leave it (best effort)
  for (int it = 0; it < 60 && outside - inside > 1e-15 * outside; ++it) {
    const double middle = 0.5 * (inside + outside);
    (violates_at(o, x + middle * direction, base) ? inside : outside) = middle;
  }
  x += outside * direction;
}

Vec3 free_axes_of(const Vec3& inverse_mass) {
  return (inverse_mass.array() > 0.0).cast<double>().matrix();
}

// Translation of the shape between two load times.
Vec3 shape_shift(const Schedule& motion, double from, double to) {
  return motion.at(to) - motion.at(from);
}

// Position-based Coulomb friction after a normal projection of `normal` metres: the slip
// relative to the shape over the step is cancelled (stick) while it is within mu * normal,
// else shortened by that much (slide). A container's wall curves inward, so the node is
// projected once more.
void apply_friction(const RigidObstacle& o, const Vec3& free, Vec3& x, const Vec3& x_start,
                    const Vec3& shift, double normal, const Vec3& base) {
  const Vec3 n = distance_from(o, base, x).normal;
  Vec3 slip = (x - x_start) - shift;
  slip = (slip - slip.dot(n) * n).cwiseProduct(free);
  const double length = slip.norm();
  if (length == 0.0) return;
  const double bound = o.friction * normal;
  x -= (length <= bound ? 1.0 : bound / length) * slip;
  project_node(o, free, x, base);
}

}  // namespace

SurfaceDistance obstacle_distance(const RigidObstacle& o, const Schedule& motion, const Vec3& x,
                                  double load_time) {
  return distance_from(o, shape_base(o, motion, load_time), x);
}

namespace {

void project_obstacle_at(const RigidObstacle& o, std::span<const Vec3> inverse_mass,
                         std::span<Vec3> x, const Vec3& base) {
  if (o.nodes.empty()) {
    for (size_t i = 0; i < x.size(); ++i)
      project_node(o, free_axes_of(inverse_mass[i]), x[i], base);
  } else {
    for (int i : o.nodes) project_node(o, free_axes_of(inverse_mass[i]), x[i], base);
  }
}

}  // namespace

void apply_contacts(const Model& model, const Controls& controls, std::span<Vec3> x,
                    double load_time) {
  for (size_t k = 0; k < model.obstacles.size(); ++k) {
    const RigidObstacle& o = model.obstacles[k];
    project_obstacle_at(o, model.inverse_mass, x,
                        shape_base(o, controls.obstacle_motion[k], load_time));
  }
}

double apply_contacts(const Model& model, const Controls& controls, std::span<Vec3> x,
                      double load_time, ContactStep& step) {
  double largest = 0.0;
  for (size_t k = 0; k < model.obstacles.size(); ++k) {
    const RigidObstacle& o = model.obstacles[k];
    const Schedule& motion = controls.obstacle_motion[k];
    const Vec3 shift = shape_shift(motion, step.start_time, load_time);
    const Vec3 base = shape_base(o, motion, load_time);
    auto one = [&](int i) {
      const Vec3 free = free_axes_of(model.inverse_mass[i]);
      const Vec3 before = x[i];
      project_node(o, free, x[i], base);
      if (x[i] == before) return;
      if (o.friction > 0.0)
        apply_friction(o, free, x[i], step.x_start[i], shift, (x[i] - before).norm(), base);
      step.touching[i] = int(k);
      step.impulse[k] += model.mass[i] * (x[i] - before) / step.dt;
      largest = std::max(largest, (x[i] - before).norm());
    };
    if (o.nodes.empty())
      for (int i = 0; i < model.node_count(); ++i) one(i);
    else
      for (int i : o.nodes) one(i);
  }
  return largest;
}

namespace {

// A node a contact stage of this step moved, against its obstacle now: the way the shape
// pushes there, the node's gap (negative inside) and the shape's velocity over the step.
struct Touch {
  const RigidObstacle& obstacle;
  int k;  // the obstacle's index
  Vec3 push;
  double gap;
  Vec3 shape_velocity;
};

// visit(i, touch) for each node in step.touching, the obstacle placed once per run of nodes
// on it; false as soon as a visit returns false.
template <class Visit>
bool each_touching(const Model& model, const Controls& controls, std::span<const Vec3> x,
                   double load_time, const ContactStep& step, Visit visit) {
  int placed = -1;  // the obstacle whose base and velocity are below
  Vec3 base = Vec3::Zero(), shape_velocity = Vec3::Zero();
  for (int i = 0; i < model.node_count(); ++i) {
    const int k = step.touching[i];
    if (k < 0) continue;
    const RigidObstacle& o = model.obstacles[size_t(k)];
    if (k != placed) {
      placed = k;
      const Schedule& motion = controls.obstacle_motion[size_t(k)];
      base = shape_base(o, motion, load_time);
      shape_velocity = shape_shift(motion, step.start_time, load_time) / step.dt;
    }
    const SurfaceDistance at = distance_from(o, base, x[i]);
    const Touch touch{o, k, o.keep_inside ? Vec3(-at.normal) : at.normal,
                      o.keep_inside ? -at.distance : at.distance, shape_velocity};
    if (!visit(i, touch)) return false;
  }
  return true;
}

}  // namespace

double apply_contact_velocities(const Model& model, const Controls& controls,
                                std::span<const Vec3> x, std::span<Vec3> v, double load_time,
                                ContactStep& step) {
  double largest = 0.0;
  if (!model.contact_pairs.empty() && step.pair_contacts)
    largest = apply_deformable_contact_velocities(model, v, *step.pair_contacts, step.pair_impulse,
                                                  step.pair_pushed);
  if (model.obstacles.empty()) return largest;
  each_touching(model, controls, x, load_time, step, [&](int i, const Touch& t) {
    const Vec3 u = v[i] - t.shape_velocity;
    const double into = -u.dot(t.push);
    if (into <= 0.0) return true;  // already leaving the surface
    Vec3 dv = into * t.push;
    const Vec3 tangential = u + into * t.push;
    const double slip = tangential.norm();
    if (slip > 0.0) dv -= std::min(1.0, t.obstacle.friction * into / slip) * tangential;
    dv = dv.cwiseProduct(free_axes_of(model.inverse_mass[i]));
    v[i] += dv;
    step.impulse[size_t(t.k)] += model.mass[i] * dv;
    largest = std::max(largest, dv.norm());
    return true;
  });
  return largest;
}

bool on_obstacles(const Model& model, const Controls& controls, std::span<const Vec3> x,
                  double load_time, const ContactStep& step, std::vector<ObstacleContact>& held) {
  constexpr double kOn = 1e-12;  // m: the projection's surface, within round-off
  held.clear();
  return each_touching(model, controls, x, load_time, step, [&](int i, const Touch& t) {
    if (t.obstacle.friction > 0.0) return false;
    if (t.gap <= kOn) held.push_back({i, t.push, 0.0});
    return true;
  });
}

bool resting_on_obstacles(const Model& model, const Controls& controls, std::span<const Vec3> x,
                          std::span<const Vec3> v, double load_time, const ContactStep& step,
                          std::vector<ObstacleContact>& held) {
  constexpr double kResting = 1e-12;  // m/s: the contact stage's zero, within round-off
  held.clear();
  return each_touching(model, controls, x, load_time, step, [&](int i, const Touch& t) {
    if (t.obstacle.friction > 0.0) return false;
    if ((v[i] - t.shape_velocity).dot(t.push) <= kResting) held.push_back({i, t.push, 0.0});
    return true;
  });
}

}  // namespace phymul
