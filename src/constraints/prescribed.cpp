#include "constraints/constraints.hpp"
#include "constraints/contact.hpp"
#include "constraints/deformable_contact.hpp"
#include "constraints/doubled.hpp"
#include "constraints/needle.hpp"

namespace phymul {

void apply_prescribed(const Model& model, std::span<Vec3> x, double load_time) {
  for (const PrescribedDisplacement& p : model.prescribed) {
    const Vec3 u = p.displacement.at(load_time);
    for (int i : p.nodes)
      for (int a = 0; a < 3; ++a)
        if (p.axes[a]) x[i][a] = model.rest_position[i][a] + u[a];
  }
}

void apply_position_constraints(const Model& model, const Controls& controls, Workspace& work,
                                std::span<Vec3> x, double load_time, std::span<Vec3> scratch) {
  apply_prescribed(model, x, load_time);
  // Contact before volumes: the volume projection moves surface nodes by a few ulps of
  // their size only, while an obstacle may push a node by millimetres.
  apply_contacts(model, controls, x, load_time);
  project_volumes(model, controls, work, x, load_time, scratch);
  // Doubled nodes last, so that they coincide exactly after every projection.
  project_doubled(model, x);
}

void apply_position_constraints(const Model& model, const Controls& controls, Workspace& work,
                                std::span<Vec3> x, double load_time, std::span<Vec3> scratch,
                                ContactStep& contact) {
  apply_prescribed(model, x, load_time);
  apply_contacts(model, controls, x, load_time, contact);
  if (!model.contact_pairs.empty())
    apply_deformable_contacts(model, x, work, *contact.pair_contacts, contact.dt,
                              contact.pair_impulse);
  if (!model.needles.empty()) apply_needles(model, controls, x, load_time, contact);
  project_volumes(model, controls, work, x, load_time, scratch, contact.x_start);
  // A node on an obstacle and on a kept volume's surface: the volume's projection moves it
  // back into the obstacle (0.2 um on the prostate, 20 um on a filling bladder). The two
  // alternate until the obstacles move no node by more than a nanometre, each round about
  // fifty times smaller: the 1e-15 m of round-off took twice the rounds (+50 % on a step).
  constexpr double kSettled = 1e-9;  // m
  constexpr int kMostRounds = 20;
  if (!model.obstacles.empty() && !model.volumes.empty()) {
    for (int round = 0; round < kMostRounds; ++round) {
      const double moved = apply_contacts(model, controls, x, load_time, contact);
      if (moved == 0.0) break;
      project_volumes(model, controls, work, x, load_time, scratch, contact.x_start);
      if (moved <= kSettled) break;
    }
  }
  project_doubled(model, x);
}

}  // namespace phymul
