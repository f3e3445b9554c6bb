// Model: compiled once from a scene (or built from its parts), read-only during a run; what
// a run changes is Data (data.hpp), after MuJoCo's mjModel / mjData split. Node data are
// arrays over all nodes of all components.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <bit>
#include <cassert>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "phymul/fem.hpp"
#include "phymul/mesh.hpp"
#include "phymul/scene.hpp"
#include "phymul/schedule.hpp"

namespace phymul {

// A subset of the rows 0..n-1 of some per-row data, with membership and rank in O(1): one bit
// a row and a count every 64 rows. Data that only some rows have (the normal pairs of flat
// neighbourhoods, say) is then stored for those rows alone, at 1.5 bits a row for the rest.
struct RowSubset {
  std::vector<std::uint64_t> bits;  // bit k % 64 of word k / 64: row k is a member
  std::vector<int> before;          // per word: members in the words before it

  // Position of row k among the members (in row order), or -1 when it is not one.
  int find(int k) const {
    assert(k >= 0 && size_t(k) < 64 * bits.size());
    const std::uint64_t word = bits[size_t(k) >> 6], bit = std::uint64_t(1) << (k & 63);
    if (!(word & bit)) return -1;
    return before[size_t(k) >> 6] + std::popcount(word & (bit - 1));
  }
};

// Deterministic parallel scatter: items (memory nodes, elements) that add into the forces of
// several nodes are cut into contiguous blocks, and the blocks coloured so that blocks of one
// colour write disjoint nodes. A colour runs in parallel; every nodal sum then keeps one
// order (colour, then item) whatever the number of threads.
struct ParallelPlan {
  std::vector<int> block_start;    // item ranges, blocks + 1 entries
  std::vector<int> colour_start;   // ranges of colour_blocks, colours + 1 entries
  std::vector<int> colour_blocks;  // block ids, by colour
  int blocks() const { return int(block_start.size()) - 1; }
};

// Local shape memory of one elastic component (DESIGN 2.1): every node is pulled towards
// an attraction position a = g + R c built from its neighbours, with f = K (a - x).
struct ShapeMemory {
  std::string component;
  double stiffness = 0.0;  // N/m
  FrameMode frame = FrameMode::polar;
  bool reaction = true;    // spread -f/n over the neighbours so momentum is kept
  std::vector<int> nodes;  // global ids of the nodes that carry a memory
  Adjacency neighbours;    // per memory node, global ids; the ordered one-ring on surfaces
  // c = R0^T (X - G0), m; G0 the rest centroid. `frame` mode only: in polar mode R0 is the
  // identity and the force pass recomputes c from the rest positions (24 bytes a node less).
  std::vector<Vec3> rest_offset;
  // Planar neighbourhoods (every surface node, flat interior ones) leave the best-fit
  // rotation free about their normal: in polar mode such nodes add the normal pair with a
  // weight (m^2). Two neighbours (positions within the row) span the node's frame: the most
  // orthogonal pair at rest, used by the `frame` mode and for flat interior normals. Only
  // the nodes that use them keep them (`framed`: the flat ones in polar mode, all of a
  // volume in frame mode), in node order: a cube's corners, not 16 bytes on every node.
  RowSubset framed;                            // memory nodes k with the two below
  std::vector<double> normal_weight;           // per framed node; zero: no normal pair
  std::vector<std::array<int, 2>> frame_pair;  // per framed node; empty on surfaces
  bool surface = false;  // neighbours are ordered rings (normal from the ring)
  ParallelPlan plan;     // memory nodes k in coloured blocks (solver/parallel_plan.hpp)
  // Polar mode's batched kernel (forces/shape_memory_batch.cpp): the memory nodes of each
  // block of `plan` reordered, the batched ones first (lanes of equal neighbour count, no
  // normal pair), then the others in node order, from batched_end[block] on, then the
  // centred ones from centred_start[block] on: nodes whose rest position is their rest
  // neighbours' centroid (a regular grid's interior), whose attraction position is the
  // current centroid whatever the rotation (add_centred_node_forces; their rotation is not
  // kept).
  std::vector<int> batch_order;
  std::vector<int> batched_end;
  std::vector<int> centred_start;
  // Every centred node's neighbours at the same offsets of global id (a structured grid's
  // interior): runs of consecutive centred nodes then go as a stencil over the coordinate
  // arrays, whole vector registers at a time.
  bool centred_on_stencil = false;
  std::array<int, 6> centred_stencil{};
};

// Explicit finite elements of one component (TLED, Miller et al. 2007): total Lagrangian,
// compressible Neo-Hookean W = mu/2 (J^-2/3 I1 - 3) + kappa/2 (J - 1)^2 (the reference FEM's
// law); linear tetrahedra, or hexahedra with one integration point and Flanagan-Belytschko
// hourglass control.
struct ExplicitFem {
  std::string component;
  // The object's law, E, nu and hexahedron: what the implicit solver (solver: newton) takes;
  // TLED uses the Neo-Hookean moduli below.
  fem::Material material;
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
  Schedule target_schedule;         // m^3 in x over time; empty: target_volume throughout
  double target_at(double load_time) const {
    return target_schedule.empty() ? target_volume : target_schedule.at(load_time).x();
  }
  // The gradient's gather (finalize): for nodes[k], the two other corners of each triangle
  // around it, in triangle order and the triangle's cyclic order, at
  // [incident_start[k], incident_start[k + 1]) of incident. Empty: the triangles' scatter.
  std::vector<int> incident_start;
  std::vector<std::array<int, 2>> incident;
  // (The velocity projection's gradient, kept for the next position projection at the same
  // positions, is the Data's: VolumeCache.)
  // The nodes it shares with earlier constraints (finalize), where alone the joint
  // projection's products of two gradients are not zero: {l, local index here, local index
  // in volumes[l]}, by l then node.
  std::vector<std::array<int, 3>> shared;
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
  // to point + length * axis (both ends rounded); probe: a capsule whose base end extends to
  // infinity backwards (open there, rounded at the tip), its tip's centre at `point`.
  using Shape = ObstacleShape;
  std::string name;  // names its monitors columns; "" = obstacle<index>
  Shape shape = Shape::plane;
  Vec3 point = Vec3::Zero();  // m, at load time 0
  Vec3 axis = Vec3::UnitZ();  // normalised by add_rigid_obstacle
  double radius = 0.0;        // m
  double length = 0.0;        // m
  Schedule motion;            // m, translation of the shape over time (empty: fixed)
  bool keep_inside = false;   // a container instead of an obstacle
  std::vector<int> nodes;     // global ids it acts on; empty = all nodes
  double friction = 0.0;      // Coulomb coefficient (>= 0) between the shape and the nodes
};

// A node against a rigid obstacle at some instant: the direction in which the obstacle can
// push it (unit) and the Coulomb coefficient between them.
struct ObstacleContact {
  int node = 0;
  Vec3 push = Vec3::Zero();
  double friction = 0.0;
};

// Two deformable components that may touch but not interpenetrate (frictionless): each
// surface node of one is kept out of the other's closed boundary, node against triangle.
struct ContactPair {
  std::array<int, 2> components{0, 0};
  std::array<std::vector<Triangle>, 2> faces;  // each component's boundary, global ids
  std::array<std::vector<int>, 2> nodes;       // each component's surface nodes, sorted
  // m: penetrations deeper than this are not looked for (half the larger mean rest edge: a
  // step moves a node by far less in any stable run). Set by finalize.
  double margin = 0.0;
};

// Nodes pulled back to their rest positions by linear springs: a compliant support (the
// soft tissue or ligaments around an organ), where a fixed node would be a rigid one.
struct SpringSupport {
  std::vector<int> nodes;
  double stiffness = 0.0;  // N/m, of each node's spring
};

// A material point of a volume cell: a combination of four of its nodes (one tetrahedron
// of the cell), weights summing to one. Where a needle's track points and target sit.
struct EmbeddedPoint {
  std::array<int, 4> nodes{0, 0, 0, 0};  // global ids
  std::array<double, 4> weights{1.0, 0.0, 0.0, 0.0};
  Vec3 at(std::span<const Vec3> x) const {
    Vec3 p = Vec3::Zero();
    for (int k = 0; k < 4; ++k) p += weights[size_t(k)] * x[size_t(nodes[size_t(k)])];
    return p;
  }
};

// A volume object a needle crosses, with its own parameters (DiMaio and Salcudean 2003).
struct NeedleTissue {
  int component = 0;
  double puncture_force = 0.0;  // N: the tip's push at which the surface gives way
  double friction = 0.0;        // N/m: kinetic friction per inserted length, along the shaft
  double cutting_force = 0.0;   // N: on the tissue at the tip while the tip advances in it
  // The component's cells as tetrahedra (hexahedra in 6, wedges in 3), global ids: where a
  // point is found and embedded.
  std::vector<std::array<int, 4>> tetrahedra;
};

// A straight rigid needle inserted along its axis (docs/needles.md): its tip at
// base + depth(t) direction. It presses the surface of the next tissue like a point contact
// until the push exceeds the tissue's puncture force; then points of the tissue met by the
// tip every `spacing` of travel are embedded in their cells and held on the shaft laterally,
// with stick-slip friction along it.
struct Needle {
  std::string name;                   // monitors columns: needle_<name>_...
  Vec3 base = Vec3::Zero();           // m: the tip at depth 0
  Vec3 direction = Vec3::UnitZ();     // unit (add_needle normalises it)
  double radius = 0.0;                // m, for display
  double spacing = 0.0;               // m of tip travel between track points
  Schedule depth;                     // m in x over time
  std::vector<NeedleTissue> tissues;  // in the order the needle meets them
  int target_component = -1;          // -1: no target
  EmbeddedPoint target;               // a point of target_component, moving with it
  int track_capacity = 0;             // most track points at once (add_needle)
};

struct Component {
  std::string name;
  ObjectType kind = ObjectType::elastic;
  // Global id of each node of the component's mesh, in mesh order. Stitching (stitch.cpp)
  // merges nodes, so a shared border node appears in the lists of both components.
  std::vector<int> nodes;
  int first_cell = 0, cell_count = 0;
  bool volumetric = true;
  std::vector<Triangle> boundary;                     // global ids; empty when the surface is open
  std::map<std::string, std::vector<int>> node_sets;  // global ids
};

// A rigid component (bone, instrument) moving as one body: its nodes' positions are set
// from the body's pose. Free bodies integrate the force and torque of the forces on their
// nodes; driven ones follow their schedules (an instrument).
struct RigidBody {
  int component = 0;
  bool driven = false;
  Schedule translation;  // m, of the rest centre of mass (driven)
  Schedule rotation;     // rad, rotation vector about the rest centre of mass (driven)
  // Filled by finalize from the node masses: the component's nodes and the nodes doubled
  // with them (Fig. 1b), which move with the body.
  std::vector<int> nodes;
  std::vector<Vec3> offset;                         // m, node position in the principal frame
  double mass = 0.0;                                // kg
  Vec3 inertia = Vec3::Zero();                      // kg m^2, principal moments
  Vec3 rest_center = Vec3::Zero();                  // m
  Eigen::Quaterniond rest_orientation{1, 0, 0, 0};  // principal frame -> world at rest
  double size = 0.0;                                // m, largest node distance from the centre
};

// Contractile fibres of an active component (muscle): polylines through its nodes whose
// segments are tension-only springs of rest length l0 (1 - a(t) ratio).
struct FibreBundle {
  int component = 0;
  Adjacency polylines;              // global node ids, in order along each fibre
  std::vector<double> rest_length;  // m, per segment, in polyline order
  double stiffness = 0.0;           // N/m, per segment
  double max_contraction = 0.0;     // ratio in (0, 1)
  Schedule activation;              // a(t) in [0, 1], in x
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
  std::vector<SpringSupport> springs;
  std::vector<PressureLoad> pressures;
  std::vector<RigidObstacle> obstacles;
  std::vector<RigidBody> rigid_bodies;
  std::vector<FibreBundle> fibres;
  std::vector<StiffnessCalibration> stiffness_calibrations;  // components given `young`
  // Doubled nodes (Fig. 1b): groups held at one position and velocity (mass-weighted).
  // Groups touching a rigid body are moved by the body instead (finalize).
  std::vector<std::array<int, 2>> doubled_pairs;   // as given (global ids)
  Adjacency doubled;                               // groups among elastic nodes (finalize)
  std::vector<std::array<int, 3>> doubled_leader;  // per group and axis: a held member or -1
  std::vector<int> rigid_body_of;                  // per node: body index or -1 (finalize)
  std::vector<ContactPair> contact_pairs;
  std::vector<Needle> needles;
  // Per node and axis: 1/m where the node is free to move along that axis, 0 where a
  // position constraint holds it. The projection of global constraints moves nodes by it.
  std::vector<Vec3> inverse_mass;
  bool coupled_volumes = false;  // some node lies on two volume constraints (set by finalize)
  // kg per node: the inertia the steps use. The masses, unless the settings scale them:
  // static relaxation's fictitious masses (relaxation_mass_scaling) or the dynamics' mass
  // scaling (mass_scaling_dt). Gravity keeps the true masses.
  std::vector<double> inertia;
  // The settings `inertia` and `inverse_mass` were derived for (finalize); make_data refuses
  // a model whose settings changed since.
  SolveMode finalized_mode = SolveMode::dynamic;
  bool finalized_relaxation_mass_scaling = true;
  std::optional<double> finalized_mass_scaling_dt;
  // The runaway guard's yardsticks (solver/runaway_guard.hpp): per node its shortest rest
  // edge where the guard watches it (infinity elsewhere), their smallest, and the diagonal of
  // the rest bounding box (m).
  std::vector<double> runaway_edge;
  double shortest_runaway_edge = 0.0;
  double size_scale = 1.0;
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
void add_spring_support(Model& model, SpringSupport springs);
void add_pressure(Model& model, PressureLoad pressure);
void add_rigid_obstacle(Model& model, RigidObstacle obstacle);
// A needle (Needle): checks its parameters, splits its tissues' cells into tetrahedra and
// sizes its track. Tissues must be volumetric, deformable components.
void add_needle(Model& model, Needle needle);
// Frictionless contact between two components with closed boundaries.
void add_contact_pair(Model& model, int component_a, int component_b);
// The boundary faces of `component` whose rest centroid lies within `radius` of the infinite
// line through axis_point along axis_direction (the paper's cylinder-shaped probe pressure).
std::vector<Triangle> faces_in_cylinder(const Model& model, int component, const Vec3& axis_point,
                                        const Vec3& axis_direction, double radius);
// A rigid component: nodes, cells and masses from the mesh and material (stiffness unused).
// A driven one follows translation and rotation (rad, rotation vector) schedules.
int add_rigid_component(Model& model, const std::string& name, const Mesh& mesh,
                        const MaterialSpec& material, bool driven = false,
                        Schedule translation = {}, Schedule rotation = {});
// Merges each pair (keep, drop) of global node ids into one node (masses add, the rest
// position is the mass-weighted mean): the shared border nodes of Fig. 1a. Node ids above
// a dropped one shift down. Call after the components and before loads and constraints.
void stitch_nodes(Model& model, const std::vector<std::array<int, 2>>& pairs);
// Pairs (a, b), a from `from`, b from `to`, whose rest positions are within tolerance (m),
// each node paired with its nearest candidate.
std::vector<std::array<int, 2>> coincident_pairs(const Model& model, const std::vector<int>& from,
                                                 const std::vector<int>& to, double tolerance);
// Holds each pair at one position and one velocity (Fig. 1b); see Model::doubled.
void add_doubled_nodes(Model& model, const std::vector<std::array<int, 2>>& pairs);
// Fibres of an active component along `direction`: the lines of its nodes parallel to it
// (nodes whose positions across the direction agree within 1e-6 of the mesh size).
void add_fibres(Model& model, int component, const Vec3& direction, double stiffness,
                double max_contraction, Schedule activation);
// Fibres along given polylines (global node ids of the component, in order).
void add_fibre_polylines(Model& model, int component, const std::vector<std::vector<int>>& lines,
                         double stiffness, double max_contraction, Schedule activation);
// Recomputes what is derived from the rest (inverse masses, inertias for the settings' mass
// scaling, rigid bodies, doubled groups, volume indexes, the runaway guard's edges); call
// after the last add_* and again after changing the settings.
void finalize(Model& model);
// Whether finalize ran for the model as it stands (its settings included).
bool finalized(const Model& model);

// Per node, the Gershgorin row sum (N/m) of the elastic stiffness at rest (shape memory,
// fibres, explicit finite elements): the stability estimate's and mass scaling's measure.
std::vector<double> stiffness_row_sums(const Model& model);

// The mesh a scene's MeshSpec describes: generated and placed by its transform, or its file as
// the loader read and placed it (std::invalid_argument when it was not read).
Mesh make_mesh(const MeshSpec& spec);

// Applies `transform` to the mesh's points (scale, rotate, translate); cell orientation is
// kept since every scale is positive.
void place_mesh(Mesh& mesh, const MeshTransform& transform);

// A scene file's description into a model; semantic problems (a node set that selects no
// node, a volume constraint on an open surface, ...) throw SceneError with their location.
Model compile_scene(const Scene& scene);

}  // namespace phymul
