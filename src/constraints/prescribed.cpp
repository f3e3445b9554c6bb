#include "constraints/constraints.hpp"
#include "constraints/contact.hpp"
#include "constraints/coupled_volume.hpp"
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
  // The volume's projection moves a node on an obstacle back into it (0.2 um on the prostate,
  // 20 um on a filling bladder): rounds until the obstacles move none above 1 nm (the
  // 1e-15 m of round-off took twice the rounds, +50 % on a step). Frictionless obstacles
  // alone: the rounds' limit in one projection first, the held nodes' pushes taken out of it.
  if (!model.obstacles.empty() && !model.volumes.empty())
    alternate_contact_and_volume(
        [&] { return apply_contacts(model, controls, x, load_time, contact); },
        [&] { project_volumes(model, controls, work, x, load_time, scratch, contact.x_start); },
        model.coupled_volumes && model.contact_pairs.empty() && model.needles.empty(),
        [&] {
          return on_obstacles(model, controls, x, load_time, contact, work.contacts) &&
                 reproject_coupled_volumes_held(model, controls, work, x, load_time, work.contacts,
                                                contact.touching, contact.impulse, contact.dt);
        },
        1e-9 /* m */);
  project_doubled(model, x);
}

}  // namespace phymul
