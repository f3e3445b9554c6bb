// Model (compiled once, read-only during a run) and State (what a step changes), after
// MuJoCo's mjModel / mjData split. Node data are arrays over all nodes of all components.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "phymul/mesh.hpp"
#include "phymul/parallel_plan.hpp"
#include "phymul/scene.hpp"

namespace phymul {

// Local shape memory of one elastic component (DESIGN 2.1): every node is pulled towards
// an attraction position a = g + R c built from its neighbours, with f = K (a - x).
struct ShapeMemory {
  std::string component;
  double stiffness = 0.0;  // N/m
  FrameMode frame = FrameMode::polar;
  bool reaction = true;           // spread -f/n over the neighbours so momentum is kept
  std::vector<int> nodes;         // global ids of the nodes that carry a memory
  Adjacency neighbours;           // per memory node, global ids; the ordered one-ring on surfaces
  std::vector<Vec3> rest_offset;  // c = R0^T (X - G0), m; G0 the rest centroid
  // Planar neighbourhoods (every surface node, flat interior ones) leave the best-fit
  // rotation free about their normal: such nodes add the normal pair with this weight (m^2).
  std::vector<double> normal_weight;  // zero for the others
  // Two neighbours (positions within the row) spanning the node's frame: the most
  // orthogonal pair at rest. Used by the `frame` mode and for flat interior normals.
  std::vector<std::array<int, 2>> frame_pair;
  bool surface = false;  // neighbours are ordered rings (normal from the ring)
  ParallelPlan plan;     // memory nodes k in coloured blocks (solver/parallel_plan.hpp)
};

// Explicit finite elements of one component (TLED, Miller et al. 2007): total Lagrangian,
// compressible Neo-Hookean W = mu/2 (J^-2/3 I1 - 3) + kappa/2 (J - 1)^2 (the reference FEM's
// law); linear tetrahedra, or hexahedra with one integration point and Flanagan-Belytschko
// hourglass control.
struct ExplicitFem {
  std::string component;
  double mu = 0.0, kappa = 0.0;  // Pa
  int nodes_per_cell = 8;        // 8 (hexahedra) or 4 (tetrahedra)
  std::vector<int> cells;        // global node ids, nodes_per_cell per cell
  std::vector<double> gradient;  // dN_a/dX at the cell centre, nodes_per_cell x 3 per cell
  std::vector<double> volume;    // m^3, reference
  std::vector<double> gamma;     // hexahedra: hourglass vectors, 8 x 4 per cell
  std::vector<double> hourglass_stiffness;  // N/m per cell
  ParallelPlan plan;                        // cells in coloured blocks
};

// Constant enclosed volume of a closed, outward-oriented surface (DESIGN 2.2).
struct VolumeConstraint {
  std::string component;
  std::vector<Triangle> triangles;  // global node ids
  std::vector<int> nodes;           // the surface's nodes, sorted
  double target_volume = 0.0;       // m^3
};

struct AppliedForce {
  std::vector<int> nodes;
  Schedule force;  // N on each node
};

struct PrescribedDisplacement {
  std::vector<int> nodes;
  std::array<bool, 3> axes{true, true, true};
  Schedule displacement;  // m, from the rest position
};

// A follower load (the paper's probe pressure): p (Pa, the x component of the schedule)
// pushes each face into the body, along minus its CURRENT outward normal, shared equally by
// its three nodes.
struct PressureLoad {
  int component = 0;
  std::vector<Triangle> faces;  // global ids, oriented outward (from Component::boundary)
  Schedule pressure;            // Pa in x; positive pushes into the body
};

// A rigid analytic shape the nodes may not enter (or, keep_inside, may not leave), enforced
// by projection after prescribed displacements and before volume constraints.
struct RigidObstacle {
  // plane: the half-space behind `point` opposite to `axis` (the outward normal, free side);
  // sphere: centre `point`; capsule: the points within `radius` of the segment from `point`
  // to point + length * axis (both ends rounded); rounded_cylinder: an endorectal probe, a
  // capsule whose base end extends to infinity backwards (open there, rounded at the tip).
  enum class Shape { plane, sphere, capsule, rounded_cylinder };
  Shape shape = Shape::plane;
  Vec3 point = Vec3::Zero();  // m, at load time 0
  Vec3 axis = Vec3::UnitZ();  // normalised by add_rigid_obstacle
  double radius = 0.0;        // m
  double length = 0.0;        // m
  Schedule motion;            // m, translation of the shape over time (empty: fixed)
  bool keep_inside = false;   // a container instead of an obstacle
  std::vector<int> nodes;     // global ids it acts on; empty = all nodes
  double friction = 0.0;      // Coulomb coefficient; not implemented yet: must be 0
};

struct Component {
  std::string name;
  int first_node = 0, node_count = 0;
  int first_cell = 0, cell_count = 0;
  bool volumetric = true;
  std::vector<Triangle> boundary;                     // global ids; empty when the surface is open
  std::map<std::string, std::vector<int>> node_sets;  // global ids
};

struct Model {
  std::vector<Vec3> rest_position;  // m
  std::vector<double> mass;         // kg
  std::vector<Cell> cells;          // global node ids (output)
  std::vector<int> cell_component;
  std::vector<Component> components;
  std::vector<ShapeMemory> shape_memory;
  std::vector<ExplicitFem> explicit_fem;
  std::vector<VolumeConstraint> volumes;
  std::vector<AppliedForce> forces;
  std::vector<PrescribedDisplacement> prescribed;
  std::vector<PressureLoad> pressures;
  std::vector<RigidObstacle> obstacles;
  // Per node and axis: 1/m where the node is free to move along that axis, 0 where a
  // position constraint holds it. The projection of global constraints moves nodes by it.
  std::vector<Vec3> inverse_mass;
  Vec3 gravity = Vec3::Zero();  // m/s^2
  double damping = 0.0;         // 1/s
  SimulationSpec settings;

  int node_count() const { return int(rest_position.size()); }
};

// Building blocks of a model (compile_scene uses them; embedding programs may too).
// Each throws std::invalid_argument with an actionable message.
// material.model chooses the elasticity: shape memory (stiffness) or explicit finite
// elements (young, poisson; hexahedra or tetrahedra only).
int add_elastic_component(Model& model, const std::string& name, const Mesh& mesh,
                          const MaterialSpec& material);
void add_volume_constraint(Model& model, int component);
void add_fixed_nodes(Model& model, const std::vector<int>& nodes);
void add_prescribed_displacement(Model& model, PrescribedDisplacement prescribed);
void add_applied_force(Model& model, AppliedForce force);
void add_pressure(Model& model, PressureLoad pressure);
void add_rigid_obstacle(Model& model, RigidObstacle obstacle);
// The boundary faces of `component` whose rest centroid lies within `radius` of the infinite
// line through axis_point along axis_direction (the paper's cylinder-shaped probe pressure).
std::vector<Triangle> faces_in_cylinder(const Model& model, int component, const Vec3& axis_point,
                                        const Vec3& axis_direction, double radius);
// Recomputes derived arrays (inverse_mass); call after the last add_*.
void finalize(Model& model);

// A scene file's description into a model; semantic problems (a node set that selects no
// node, a volume constraint on an open surface, ...) throw SceneError with their location.
Model compile_scene(const Scene& scene);

struct State {
  double time = 0.0;  // s
  long step = 0;
  std::vector<Vec3> x, v;                    // m, m/s
  std::vector<Vec3> f;                       // N, every force but damping, at (x, time)
  std::vector<Eigen::Quaterniond> rotation;  // per shape-memory node: last best-fit rotation
  double shape_memory_energy = 0.0;          // J, sum of K |a - x|^2 / 2 at the last force pass
};

State make_state(const Model& model);

// Force (N) the obstacle exerts on the body: minus State::f, on the free axes, summed over the
// nodes it acts on that touch its surface (within 1e-12 m) at State::time. Valid at
// equilibrium only (after relax), where the contact force is all that balances them.
Vec3 obstacle_force(const Model& model, const State& state, int obstacle);

}  // namespace phymul
