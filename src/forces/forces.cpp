#include "phymul/forces.hpp"

#include "forces/active_fibres.hpp"
#include "forces/explicit_fem.hpp"
#include "forces/pressure.hpp"
#include "forces/shape_memory.hpp"
#include "model/thread_team.hpp"
#include "model/workspace.hpp"

namespace phymul {
namespace {

// Each node's spring pulls it back to its rest position; returns the springs' energy (J).
double add_spring_forces(const SpringSupport& springs, std::span<const Vec3> rest,
                         std::span<const Vec3> x, std::span<Vec3> f) {
  double energy = 0.0;
  for (int i : springs.nodes) {
    const Vec3 stretch = x[size_t(i)] - rest[size_t(i)];
    f[size_t(i)] -= springs.stiffness * stretch;
    energy += 0.5 * springs.stiffness * stretch.squaredNorm();
  }
  return energy;
}

}  // namespace

void compute_forces(const Model& model, Data& s, double load_time) {
  Workspace& w = *s.work;
  const int n = model.node_count();
  {
    // Over the coordinates as one array: the lanes take a node's three products at once.
    double* __restrict f = s.f.data()->data();
    const double* __restrict mass = model.mass.data();
    const double gx = model.gravity.x(), gy = model.gravity.y(), gz = model.gravity.z();
    for_each_lane(n, team_pays(n, 4096), [=](int i) {
      f[3 * i] = mass[i] * gx;
      f[3 * i + 1] = mass[i] * gy;
      f[3 * i + 2] = mass[i] * gz;
    });
  }
  for (const AppliedForce& load : model.forces) {
    const Vec3 fi = load.force.at(load_time);
    for (int i : load.nodes) s.f[i] += fi;
  }
  for (size_t k = 0; k < model.pressures.size(); ++k)
    add_pressure(model.pressures[k], s.controls.pressure[k].at(load_time).x(), s.x, s.f);
  if (!s.controls.applied_force.empty())
    for (int i = 0; i < n; ++i) s.f[size_t(i)] += s.controls.applied_force[size_t(i)];
  s.shape_memory_energy = 0.0;
  size_t first_rotation = 0;
  for (size_t k = 0; k < model.shape_memory.size(); ++k) {
    const ShapeMemory& m = model.shape_memory[k];
    std::span<Eigen::Quaterniond> rotations(s.rotation.data() + first_rotation, m.nodes.size());
    s.shape_memory_energy += add_shape_memory_forces(m, model.rest_position, s.x, rotations, s.f,
                                                     w.shape_memory_blocks[k]);
    first_rotation += m.nodes.size();
  }
  for (const SpringSupport& springs : model.springs)
    s.shape_memory_energy += add_spring_forces(springs, model.rest_position, s.x, s.f);
  for (const FibreBundle& fibres : model.fibres) add_fibre_forces(fibres, s.x, load_time, s.f);
  for (size_t k = 0; k < model.explicit_fem.size(); ++k)
    s.shape_memory_energy += add_explicit_fem_forces(model.explicit_fem[k], model.rest_position,
                                                     s.x, s.f, w.fem_blocks[k]);
}

}  // namespace phymul
