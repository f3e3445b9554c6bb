#include "solver/implicit_friction.hpp"

#include <algorithm>
#include <cmath>

#include "constraints/contact.hpp"
#include "model/workspace.hpp"
#include "phymul/data.hpp"

namespace phymul {
namespace {

// 1 on the axes the solve moves the node along, 0 on held ones.
Vec3 free_axes(const ImplicitSystem& s, int i) {
  Vec3 f;
  for (int a = 0; a < 3; ++a) f[a] = s.unknown[size_t(a)][size_t(i)] >= 0 ? 1.0 : 0.0;
  return f;
}

// v without its part along the unit n, on the free axes.
Vec3 tangential(const Vec3& v, const Vec3& n, const Vec3& free) {
  return (v - v.dot(n) * n).cwiseProduct(free);
}

// Two unit tangents of the unit normal n, orthogonal to each other.
void tangents(const Vec3& n, Vec3& t1, Vec3& t2) {
  int least = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(n[a]) < std::abs(n[least])) least = a;
  t1 = Vec3::Unit(least).cross(n).normalized();
  t2 = n.cross(t1);
}

// The sticking node's tangent rows: its slip over the step brought to zero by the solve.
void add_stick_rows(ImplicitSystem& s, int node, const Vec3& push, const Vec3& slip, int obstacle,
                    int normal_row) {
  Vec3 t[2];
  tangents(push, t[0], t[1]);
  for (const Vec3& along : t) {
    ImplicitSystem::Contact row;
    row.nodes[0] = node;
    row.push = along;
    row.gap = along.dot(slip);
    row.obstacle = obstacle;
    row.normal_row = normal_row;
    s.active.push_back(row);
  }
}

}  // namespace

bool with_friction(const Model& model) {
  return std::any_of(model.obstacles.begin(), model.obstacles.end(),
                     [](const RigidObstacle& o) { return o.friction > 0.0; });
}

void prepare_implicit_friction(const Model& model, ImplicitSystem& s) {
  if (!with_friction(model)) {
    s.sliding.clear();
    return;
  }
  s.sliding.assign(size_t(model.node_count()), 0);
  s.obstacle_shift.assign(model.obstacles.size(), Vec3::Zero());
}

void start_friction(const Model& model, const Data& d, ImplicitSystem& s, double load_time) {
  if (s.sliding.empty()) return;
  for (size_t k = 0; k < model.obstacles.size(); ++k) {
    const Schedule& motion = d.controls.obstacle_motion[k];
    s.obstacle_shift[k] = motion.at(load_time) - motion.at(d.load_time);
  }
}

Vec3 add_friction(const Model& model, const Data& d, ImplicitSystem& s, int node, const Vec3& push,
                  int obstacle, double normal, int normal_row) {
  const Workspace& w = *d.work;
  const size_t i = size_t(node);
  const Vec3 free = free_axes(s, node);
  const Vec3 pull = tangential(node_value(s, s.residual, node), push, free);
  const Vec3 slip =
      tangential(d.x[i] - w.x_start[i] - s.obstacle_shift[size_t(obstacle)], push, free);
  // The force that would hold the node where it started (relative to the shape): the pull,
  // and the backward-Euler inertia's spring-back from its slip. Within the cone it sticks,
  // else it slides against that force. Its direction is continuous where a slip's is not (a
  // node sliding to a halt), and at a fixed point it is Coulomb's either way: a sticking node
  // has no slip, and a sliding one slips along its pull.
  const double h = s.h;
  const Vec3 hold = pull + model.inertia[i] * (1.0 + model.damping * h) / (h * h) * slip;
  const double bound = model.obstacles[size_t(obstacle)].friction * normal;
  s.sliding[i] = hold.norm() > bound;
  const Vec3 friction = s.sliding[i] ? Vec3(-bound * hold.normalized()) : Vec3(-hold);
  if (!s.sliding[i]) add_stick_rows(s, node, push, slip, obstacle, normal_row);
  gather_node(s, node, friction, s.residual);
  return friction;
}

}  // namespace phymul
