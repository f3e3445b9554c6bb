#include "phymul/model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "model/explicit_fem_cells.hpp"
#include "model/finalize.hpp"
#include "model/shape_memory_rest.hpp"

namespace phymul {
namespace {

void check_node_ids(const Model& model, const std::vector<int>& nodes, const char* what) {
  for (int i : nodes)
    if (i < 0 || i >= model.node_count())
      throw std::invalid_argument(fmt::format(
          "{}: node {} is out of range (the model has {} nodes)", what, i, model.node_count()));
}

// Node masses from the material: density times lumped cell volume, or a total mass spread
// in proportion to the lumped cell measure (the only choice for a surface).
std::vector<double> node_masses(const std::string& name, const Mesh& mesh,
                                const MaterialSpec& material) {
  std::vector<double> share = lumped_measure(mesh);
  double total_measure = 0.0;
  for (double s : share) total_measure += s;
  if (material.density) {
    if (!mesh.volumetric())
      throw std::invalid_argument(fmt::format(
          "object '{}': 'density' needs a volume mesh; give the total 'mass' of a surface", name));
    for (double& s : share) s *= *material.density;
  } else if (material.mass) {
    for (double& s : share) s *= *material.mass / total_measure;
  } else {
    throw std::invalid_argument(
        fmt::format("object '{}': the material needs 'density' or 'mass'", name));
  }
  return share;
}

// Surfaces sharing a node disturb each other's projection: they are projected together.
void mark_coupled_volumes(Model& model) {
  std::vector<char> seen(model.rest_position.size(), 0);
  model.coupled_volumes = false;
  for (const VolumeConstraint& c : model.volumes)
    for (int i : c.nodes) {
      if (seen[size_t(i)]) model.coupled_volumes = true;
      seen[size_t(i)] = 1;
    }
  index_shared_volume_nodes(model);
}

// The node's inertia and the inverse mass of its free axes (held axes stay held).
void give_inertia(Model& model, int i, double inertia) {
  model.inertia[size_t(i)] = inertia;
  for (int a = 0; a < 3; ++a)
    if (model.inverse_mass[i][a] != 0.0) model.inverse_mass[i][a] = 1.0 / inertia;
}

// Static equilibrium does not depend on the masses; the time to reach it by pseudo-dynamics
// does. Lumped masses make corner and edge nodes 8 and 4 times lighter than interior ones
// while their stiffness is about the same: they alone set the stable step. Masses
// proportional to each node's stiffness row give every node the largest frequency, so the
// step stays and the slow modes speed up (Underwood's dynamic relaxation).
void scale_masses_for_relaxation(Model& model) {
  const std::vector<double> row = stiffness_row_sums(model);
  double omega2 = 0.0;
  for (int i = 0; i < model.node_count(); ++i) omega2 = std::max(omega2, row[i] / model.inertia[i]);
  if (omega2 == 0.0) return;
  for (int i = 0; i < model.node_count(); ++i) {
    // No stiffness, or nothing free to move (held, rigid): keeps its mass.
    if (row[i] == 0.0 || model.inverse_mass[i] == Vec3::Zero()) continue;
    give_inertia(model, i, row[i] / omega2);
  }
}

// Explicit FEM's mass scaling: the few light nodes that alone set the stable step (the
// corners of a mapped grid, 8 times lighter than interior nodes) get the inertia that lifts
// their Gershgorin limit to `target` (s). Equilibria do not change; the dynamics of those
// nodes are slowed (added_inertia says by how much mass).
void scale_masses_to(Model& model, double target) {
  const std::vector<double> row = stiffness_row_sums(model);
  for (int i = 0; i < model.node_count(); ++i) {
    const double needed = row[i] * target * target / 4.0;  // 2 / sqrt(row / m) = target
    if (needed > model.inertia[size_t(i)]) give_inertia(model, i, needed);
  }
}

double bounding_diagonal(const std::vector<Vec3>& p) {
  if (p.empty()) return 1.0;
  const auto [lo, hi] = bounding_box(p);
  return std::max((hi - lo).norm(), 1e-12);
}

double mean_edge(const std::vector<Triangle>& faces, const std::vector<Vec3>& x) {
  double sum = 0.0;
  for (const Triangle& t : faces)
    sum += (x[t[1]] - x[t[0]]).norm() + (x[t[2]] - x[t[1]]).norm() + (x[t[0]] - x[t[2]]).norm();
  return faces.empty() ? 0.0 : sum / (3.0 * double(faces.size()));
}

// Nodes, masses, cells, boundary and node sets of a component's mesh, appended to the model.
int add_mesh(Model& model, const std::string& name, const Mesh& mesh,
             const MaterialSpec& material) {
  const int first_node = model.node_count();
  Component c;
  c.name = name;
  c.nodes.resize(mesh.points.size());
  for (size_t i = 0; i < mesh.points.size(); ++i) c.nodes[i] = first_node + int(i);
  c.first_cell = int(model.cells.size());
  c.cell_count = int(mesh.cells.size());
  c.volumetric = mesh.volumetric();
  const std::vector<Triangle> boundary = boundary_triangles(mesh);
  if (is_closed(boundary)) {
    c.boundary.reserve(boundary.size());
    for (const Triangle& t : boundary)
      c.boundary.push_back({t[0] + first_node, t[1] + first_node, t[2] + first_node});
  }
  for (const auto& [set, ids] : mesh.node_sets) {
    auto& global = c.node_sets[set];
    for (int i : ids) global.push_back(i + first_node);
  }

  const std::vector<double> masses = node_masses(name, mesh, material);
  // Exact sizes: per-node arrays grown by doubling would keep up to twice their bytes.
  model.rest_position.reserve(model.rest_position.size() + mesh.points.size());
  model.mass.reserve(model.mass.size() + mesh.points.size());
  model.cells.reserve(model.cells.size() + mesh.cells.size());
  model.cell_component.reserve(model.cell_component.size() + mesh.cells.size());
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    model.rest_position.push_back(mesh.points[i]);
    model.mass.push_back(masses[i]);
  }
  const int component = int(model.components.size());
  for (Cell cell : mesh.cells) {
    for (int k = 0; k < node_count(cell.type); ++k) cell.nodes[k] += first_node;
    model.cells.push_back(cell);
    model.cell_component.push_back(component);
  }
  model.components.push_back(std::move(c));
  return component;
}

}  // namespace

int add_elastic_component(Model& model, const std::string& name, const Mesh& mesh,
                          const MaterialSpec& material) {
  validate(mesh);
  if (material.model == ElasticModel::shape_memory && !(material.stiffness.value_or(0.0) > 0.0))
    throw std::invalid_argument(fmt::format(
        "object '{}': 'stiffness' must be > 0 N/m (got {})", name,
        material.stiffness ? fmt::format("{} N/m", *material.stiffness) : std::string("none")));
  const int first_node = model.node_count();
  const int component = add_mesh(model, name, mesh, material);
  if (material.model == ElasticModel::fem)
    model.explicit_fem.push_back(
        build_explicit_fem(name, mesh, first_node, material, model.rest_position));
  else
    model.shape_memory.push_back(
        build_shape_memory(name, mesh, first_node, material, model.rest_position));
  return component;
}

int add_rigid_component(Model& model, const std::string& name, const Mesh& mesh,
                        const MaterialSpec& material, bool driven, Schedule translation,
                        Schedule rotation) {
  validate(mesh);
  const int component = add_mesh(model, name, mesh, material);
  model.components[component].kind = ObjectType::rigid;
  RigidBody body;
  body.component = component;
  body.driven = driven;
  body.translation = std::move(translation);
  body.rotation = std::move(rotation);
  model.rigid_bodies.push_back(std::move(body));
  return component;
}

void add_volume_constraint(Model& model, int component) {
  const Component& c = model.components.at(size_t(component));
  if (c.boundary.empty())
    throw std::invalid_argument(fmt::format(
        "object '{}': a volume constraint needs a closed surface, and its surface is open "
        "(some edge is not shared by exactly two faces)",
        c.name));
  VolumeConstraint v;
  v.component = c.name;
  v.triangles = c.boundary;
  for (const Triangle& t : v.triangles) v.nodes.insert(v.nodes.end(), t.begin(), t.end());
  std::sort(v.nodes.begin(), v.nodes.end());
  v.nodes.erase(std::unique(v.nodes.begin(), v.nodes.end()), v.nodes.end());
  v.nodes.shrink_to_fit();  // three times the surface nodes before the dedup
  v.target_volume = enclosed_volume(model.rest_position, v.triangles);
  model.volumes.push_back(std::move(v));
}

void add_fixed_nodes(Model& model, const std::vector<int>& nodes) {
  add_prescribed_displacement(model, {nodes, {true, true, true}, Schedule::constant(Vec3::Zero())});
}

void add_prescribed_displacement(Model& model, PrescribedDisplacement prescribed) {
  check_node_ids(model, prescribed.nodes, "prescribed displacement");
  model.prescribed.push_back(std::move(prescribed));
}

void add_applied_force(Model& model, AppliedForce force) {
  check_node_ids(model, force.nodes, "applied force");
  model.forces.push_back(std::move(force));
}

void add_spring_support(Model& model, SpringSupport springs) {
  check_node_ids(model, springs.nodes, "spring support");
  if (!(springs.stiffness > 0.0 && std::isfinite(springs.stiffness)))
    throw std::invalid_argument(
        fmt::format("spring support: stiffness {} N/m is not > 0", springs.stiffness));
  model.springs.push_back(std::move(springs));
}

void add_pressure(Model& model, PressureLoad pressure) {
  if (pressure.component < 0 || pressure.component >= int(model.components.size()))
    throw std::invalid_argument(
        fmt::format("pressure: component {} is out of range ({} components)", pressure.component,
                    model.components.size()));
  for (const Triangle& t : pressure.faces)
    check_node_ids(model, std::vector<int>(t.begin(), t.end()), "pressure");
  model.pressures.push_back(std::move(pressure));
}

void add_rigid_obstacle(Model& model, RigidObstacle obstacle) {
  using Shape = RigidObstacle::Shape;
  check_node_ids(model, obstacle.nodes, "rigid obstacle");
  const bool needs_axis = obstacle.shape != Shape::sphere;
  if (needs_axis && !(obstacle.axis.norm() > 0.0))
    throw std::invalid_argument("rigid obstacle: 'axis' must be a non-zero vector");
  if (obstacle.axis.norm() > 0.0) obstacle.axis.normalize();
  if (obstacle.shape != Shape::plane && !(obstacle.radius > 0.0))
    throw std::invalid_argument(
        fmt::format("rigid obstacle: 'radius' must be > 0 m (got {})", obstacle.radius));
  if ((obstacle.shape == Shape::capsule || obstacle.shape == Shape::probe) &&
      !(obstacle.length >= 0.0))
    throw std::invalid_argument(
        fmt::format("rigid obstacle: 'length' must be >= 0 m (got {})", obstacle.length));
  if (!(obstacle.friction >= 0.0) || !std::isfinite(obstacle.friction))
    throw std::invalid_argument(fmt::format(
        "rigid obstacle: 'friction' must be a finite value >= 0 (got {})", obstacle.friction));
  model.obstacles.push_back(std::move(obstacle));
}

void add_contact_pair(Model& model, int component_a, int component_b) {
  const int count = int(model.components.size());
  if (component_a < 0 || component_a >= count || component_b < 0 || component_b >= count ||
      component_a == component_b)
    throw std::invalid_argument(
        fmt::format("contact: needs two distinct components out of {} (got {} and {})", count,
                    component_a, component_b));
  ContactPair pair;
  pair.components = {component_a, component_b};
  for (int side = 0; side < 2; ++side) {
    const Component& c = model.components[size_t(pair.components[size_t(side)])];
    // The contact moves its nodes by their inverse masses, which a rigid body's nodes do not
    // have: a free body would pass through (its motion takes no contact impulse yet).
    for (const RigidBody& body : model.rigid_bodies)
      if (body.component == pair.components[size_t(side)] && !body.driven)
        throw std::invalid_argument(fmt::format(
            "contact: the rigid object '{}' is free (no 'motion'), and a contact does not move a "
            "free rigid body yet: give it a 'motion' (motion: {{}} holds it in place), or make "
            "it an obstacle",
            c.name));
    if (c.boundary.empty())
      throw std::invalid_argument(
          fmt::format("contact: object '{}' has no closed boundary surface to touch with", c.name));
    pair.faces[size_t(side)] = c.boundary;
    std::vector<int>& nodes = pair.nodes[size_t(side)];
    for (const Triangle& t : c.boundary) nodes.insert(nodes.end(), t.begin(), t.end());
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  }
  model.contact_pairs.push_back(std::move(pair));
}

void finalize(Model& model) {
  model.inverse_mass.assign(model.rest_position.size(), Vec3::Zero());
  for (int i = 0; i < model.node_count(); ++i) {
    if (!(model.mass[i] > 0.0))
      throw std::invalid_argument(fmt::format(
          "node {} has mass {} kg: every node must have a positive mass", i, model.mass[i]));
    model.inverse_mass[i].setConstant(1.0 / model.mass[i]);
  }
  for (const PrescribedDisplacement& p : model.prescribed)
    for (int i : p.nodes)
      for (int a = 0; a < 3; ++a)
        if (p.axes[a]) model.inverse_mass[i][a] = 0.0;
  // Rigid bodies first: a doubled group touching one moves with it.
  finalize_rigid_bodies(model);
  finalize_doubled(model);
  mark_coupled_volumes(model);
  for (VolumeConstraint& c : model.volumes) index_volume_faces(c);
  // Penetrations deeper than half a mean rest edge are not looked for: a step moves a node by
  // far less than that in any stable run.
  for (ContactPair& pair : model.contact_pairs)
    pair.margin = 0.5 * std::max(mean_edge(pair.faces[0], model.rest_position),
                                 mean_edge(pair.faces[1], model.rest_position));
  // The inertia the steps use: gravity keeps the true masses.
  const SimulationSpec& s = model.settings;
  model.inertia = model.mass;
  if (s.mode == SolveMode::static_equilibrium && s.relaxation_mass_scaling)
    scale_masses_for_relaxation(model);
  if (s.mode == SolveMode::dynamic && s.mass_scaling_dt) scale_masses_to(model, *s.mass_scaling_dt);
  model.finalized_mode = s.mode;
  model.finalized_relaxation_mass_scaling = s.relaxation_mass_scaling;
  model.finalized_mass_scaling_dt = s.mass_scaling_dt;
  model.runaway_edge = runaway_edges(model);
  model.shortest_runaway_edge =
      model.runaway_edge.empty()
          ? std::numeric_limits<double>::infinity()
          : *std::min_element(model.runaway_edge.begin(), model.runaway_edge.end());
  model.size_scale = bounding_diagonal(model.rest_position);
}

bool finalized(const Model& model) {
  const SimulationSpec& s = model.settings;
  return model.inverse_mass.size() == model.rest_position.size() &&
         model.inertia.size() == model.rest_position.size() && model.finalized_mode == s.mode &&
         model.finalized_relaxation_mass_scaling == s.relaxation_mass_scaling &&
         model.finalized_mass_scaling_dt == s.mass_scaling_dt;
}

}  // namespace phymul
