#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <stdexcept>

#include "model/finalize.hpp"

namespace phymul {
namespace {

// The nodes each body moves: its component's, then every doubled group touching them.
// Returns, per node, the node whose rest position places it in the body: a doubled partner
// takes its rigid partner's, so that the two coincide to the last bit.
std::vector<int> assign_nodes(Model& model) {
  const int n = model.node_count();
  model.rigid_body_of.assign(size_t(n), -1);
  for (int b = 0; b < int(model.rigid_bodies.size()); ++b) {
    const Component& c = model.components.at(size_t(model.rigid_bodies[b].component));
    for (int i : c.nodes) {
      if (model.rigid_body_of[i] >= 0 && model.rigid_body_of[i] != b)
        throw std::invalid_argument(fmt::format(
            "node {} belongs to two rigid components ('{}' and '{}'); link rigid components "
            "by an elastic one",
            i, model.components[model.rigid_bodies[model.rigid_body_of[i]].component].name,
            c.name));
      model.rigid_body_of[i] = b;
    }
  }
  std::vector<int> anchor(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) anchor[i] = i;
  for (const auto& group : doubled_groups(model)) {
    int body = -1, rigid_member = -1;
    for (int i : group) {
      const int other = model.rigid_body_of[i];
      if (other < 0) continue;
      rigid_member = i;
      if (body >= 0 && other != body)
        throw std::invalid_argument(fmt::format(
            "doubled nodes join two rigid components ('{}' and '{}'); link rigid components "
            "by an elastic one",
            model.components[model.rigid_bodies[body].component].name,
            model.components[model.rigid_bodies[other].component].name));
      body = other;
    }
    if (body >= 0)
      for (int i : group) model.rigid_body_of[i] = body, anchor[i] = rigid_member;
  }
  for (RigidBody& r : model.rigid_bodies) r.nodes.clear();
  for (int i = 0; i < n; ++i)
    if (model.rigid_body_of[i] >= 0) model.rigid_bodies[model.rigid_body_of[i]].nodes.push_back(i);
  return anchor;
}

void compute_inertia(const Model& model, const std::vector<int>& anchor, RigidBody& r) {
  const std::string& name = model.components[r.component].name;
  r.mass = 0.0;
  Vec3 moment = Vec3::Zero();
  for (int i : r.nodes)
    r.mass += model.mass[i], moment += model.mass[i] * model.rest_position[anchor[i]];
  if (!(r.mass > 0.0))
    throw std::invalid_argument(fmt::format("rigid component '{}' has no mass", name));
  r.rest_center = moment / r.mass;
  Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
  for (int i : r.nodes) {
    const Vec3 d = model.rest_position[anchor[i]] - r.rest_center;
    I += model.mass[i] * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(I);
  r.inertia = eig.eigenvalues();
  if (!(r.inertia.minCoeff() > 1e-9 * r.inertia.maxCoeff()))
    throw std::invalid_argument(fmt::format(
        "rigid component '{}': its nodes lie on one line, so its inertia is singular", name));
  Eigen::Matrix3d axes = eig.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) *= -1.0;  // a proper rotation
  r.rest_orientation = Eigen::Quaterniond(axes).normalized();
  r.offset.clear();
  r.size = 0.0;
  for (int i : r.nodes) {
    const Vec3 d = model.rest_position[anchor[i]] - r.rest_center;
    r.offset.push_back(axes.transpose() * d);
    r.size = std::max(r.size, d.norm());
  }
}

}  // namespace

void finalize_rigid_bodies(Model& model) {
  const std::vector<int> anchor = assign_nodes(model);
  for (RigidBody& r : model.rigid_bodies) {
    compute_inertia(model, anchor, r);
    for (int i : r.nodes) model.inverse_mass[i].setZero();
  }
  for (const PrescribedDisplacement& p : model.prescribed)
    for (int i : p.nodes)
      if (model.rigid_body_of[i] >= 0)
        throw std::invalid_argument(fmt::format(
            "node {} of rigid component '{}' has a prescribed displacement; a rigid component "
            "is held or moved as a whole by its 'motion'",
            i, model.components[model.rigid_bodies[model.rigid_body_of[i]].component].name));
}

}  // namespace phymul
