#include "solver/implicit_bodies.hpp"

#include <algorithm>
#include <utility>

#include "model/workspace.hpp"
#include "solver/rigid.hpp"

namespace phymul {
namespace {

// The rotation vector (rad, world frame) that turns `from` into `to`.
Vec3 turn_between(const Eigen::Quaterniond& from, const Eigen::Quaterniond& to) {
  const Eigen::AngleAxisd turn(to * from.conjugate());
  return turn.angle() * turn.axis();
}

bool is_free(const ImplicitSystem::Body& b) { return b.move[0] >= 0; }

// A body's (move, turn) values of a field given per axis over the unknowns.
std::pair<Vec3, Vec3> body_values(const ImplicitSystem::Body& b,
                                  const std::array<Eigen::VectorXd, 3>& field) {
  Vec3 move, turn;
  for (int a = 0; a < 3; ++a)
    move[a] = field[size_t(a)][b.move[size_t(a)]], turn[a] = field[size_t(a)][b.turn[size_t(a)]];
  return {move, turn};
}

}  // namespace

void gather_bodies(const Model& model, const Data& d, const ImplicitSystem& s,
                   std::span<const Vec3> field, std::array<Eigen::VectorXd, 3>& out) {
  for (size_t k = 0; k < s.body.size(); ++k) {
    const ImplicitSystem::Body& b = s.body[k];
    if (!is_free(b)) continue;
    Vec3 force = Vec3::Zero(), moment = Vec3::Zero();
    for (int i : model.rigid_bodies[k].nodes) {
      force += field[size_t(i)];
      moment += (d.x[size_t(i)] - d.bodies[k].center).cross(field[size_t(i)]);
    }
    moment = d.bodies[k].orientation.conjugate() * moment;  // in the body's frame
    for (int a = 0; a < 3; ++a) {
      out[size_t(a)][b.move[size_t(a)]] += force[a];
      out[size_t(a)][b.turn[size_t(a)]] += moment[a];
    }
  }
}

void add_body_inertia(const Model& model, const Data& d, ImplicitSystem& s, double h) {
  const double c = model.damping;
  for (size_t k = 0; k < s.body.size(); ++k) {
    const ImplicitSystem::Body& b = s.body[k];
    if (!is_free(b)) continue;
    const RigidBody& r = model.rigid_bodies[k];
    const RigidBodyState& now = d.bodies[k];
    const Vec3 move = b.momentum / h - (1.0 / h + c) * r.mass * (now.center - b.center) / h;
    const Eigen::Quaterniond to_body = now.orientation.conjugate();
    const Vec3 turn =
        to_body * b.angular_momentum / h -
        (1.0 / h + c) *
            r.inertia.cwiseProduct(to_body * turn_between(b.orientation, now.orientation)) / h;
    for (int a = 0; a < 3; ++a) {
      s.residual[size_t(a)][b.move[size_t(a)]] += move[a];
      s.residual[size_t(a)][b.turn[size_t(a)]] += turn[a];
    }
  }
}

double largest_body_residual2(const Model& model, const ImplicitSystem& s) {
  double largest2 = 0.0;
  for (size_t k = 0; k < s.body.size(); ++k) {
    const ImplicitSystem::Body& b = s.body[k];
    if (!is_free(b)) continue;
    const auto [force, moment] = body_values(b, s.residual);
    const double size = model.rigid_bodies[k].size;
    largest2 = std::max({largest2, force.squaredNorm(), moment.squaredNorm() / (size * size)});
  }
  return largest2;
}

void start_bodies(const Model& model, Data& d, ImplicitSystem& s, double h, double load_time) {
  if (model.rigid_bodies.empty()) return;
  for (size_t k = 0; k < s.body.size(); ++k) {
    const RigidBodyState& now = d.bodies[k];
    ImplicitSystem::Body& b = s.body[k];
    b.center = now.center, b.orientation = now.orientation;
    b.momentum = now.momentum, b.angular_momentum = now.angular_momentum;
  }
  drift_rigid_bodies(model, d, h, load_time);
}

void move_bodies(const Model& model, Data& d, const ImplicitSystem& s, double alpha) {
  if (model.rigid_bodies.empty()) return;
  for (size_t k = 0; k < s.body.size(); ++k) {
    const ImplicitSystem::Body& b = s.body[k];
    if (!is_free(b)) continue;
    const auto [move, turn] = body_values(b, s.correction);
    RigidBodyState& now = d.bodies[k];
    now.center += alpha * move;
    const double angle = alpha * turn.norm();
    if (angle > 0.0)  // the turn is in the body's frame
      now.orientation =
          (now.orientation * Eigen::Quaterniond(Eigen::AngleAxisd(angle, turn.normalized())))
              .normalized();
  }
  place_rigid_nodes(model, d);
}

void end_bodies(const Model& model, Data& d, const ImplicitSystem& s, double h) {
  if (model.rigid_bodies.empty()) return;
  for (size_t k = 0; k < s.body.size(); ++k) {
    const ImplicitSystem::Body& b = s.body[k];
    if (!is_free(b)) continue;
    const RigidBody& r = model.rigid_bodies[k];
    RigidBodyState& now = d.bodies[k];
    now.momentum = r.mass * (now.center - b.center) / h;
    const Eigen::Quaterniond& q = now.orientation;
    now.angular_momentum =
        q * Vec3(r.inertia.cwiseProduct(q.conjugate() * turn_between(b.orientation, q))) / h;
  }
  place_rigid_nodes(model, d);
}

}  // namespace phymul
