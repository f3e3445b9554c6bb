#include <map>

#include "phymul/simulation.hpp"

namespace phymul {

fem::Problem newton_problem(const Model& model) {
  fem::Problem p;
  p.mesh.points = model.rest_position;
  for (const ExplicitFem& e : model.explicit_fem) {
    const int material = int(p.materials.size());
    p.materials.push_back(e.material);
    const int n = e.nodes_per_cell;
    for (size_t k = 0; k < e.volume.size(); ++k) {
      Cell cell;
      cell.type = n == 8 ? CellType::hexa : CellType::tetra;
      for (int a = 0; a < n; ++a) cell.nodes[size_t(a)] = e.cells[k * size_t(n) + size_t(a)];
      p.mesh.cells.push_back(cell);
      p.cell_material.push_back(material);
    }
  }
  const double end = model.settings.duration;
  // A component prescribed twice takes the last value, as the relaxation's projection does.
  std::map<int, double> prescribed;
  for (const PrescribedDisplacement& d : model.prescribed) {
    const Vec3 value = d.displacement.at(end);
    for (int i : d.nodes)
      for (int a = 0; a < 3; ++a)
        if (d.axes[size_t(a)]) prescribed[3 * i + a] = value[a];
  }
  for (const auto& [dof, value] : prescribed) p.prescribed.push_back({dof / 3, dof % 3, value});
  p.nodal_force.assign(model.rest_position.size(), Vec3::Zero());
  for (const AppliedForce& f : model.forces) {
    const Vec3 force = f.force.at(end);
    for (int i : f.nodes) p.nodal_force[size_t(i)] += force;
  }
  for (int i = 0; i < model.node_count(); ++i)
    p.nodal_force[size_t(i)] += model.mass[size_t(i)] * model.gravity;
  p.load_steps = model.settings.load_steps;
  p.force_tolerance = model.settings.tolerance;
  return p;
}

}  // namespace phymul
