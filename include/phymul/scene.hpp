// Scenes: the plain description of what to simulate, as a scene file says it (YAML, read by
// scene_io.hpp's load_scene) or as a program builds it. Turning it into a Model is
// compile_scene (model.hpp).
#pragma once

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "phymul/fem.hpp"
#include "phymul/mesh.hpp"
#include "phymul/schedule.hpp"

namespace phymul {

struct SourceLoc {
  std::string file;
  int line = 0;    // 1-based; 0 when unknown
  int column = 0;  // 1-based
};

// One problem found in an input: "file:line:column: message".
struct Diagnostic {
  SourceLoc loc;
  std::string message;
  std::string str() const;
};

// Thrown with every problem found, not just the first.
class SceneError : public std::runtime_error {
 public:
  explicit SceneError(std::vector<Diagnostic> diagnostics);
  const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }

 private:
  std::vector<Diagnostic> diagnostics_;
};

// verlet, newton_cotes: explicit; implicit: backward Euler by local/global iterations
// (solver/implicit_step.hpp), stable at any dt.
enum class Integrator { verlet, newton_cotes, implicit };
enum class SolveMode { dynamic, static_equilibrium };
enum class FrameMode { polar, frame };
enum class Relaxation { fire, kinetic, viscous };
// How static mode finds the equilibrium: damped pseudo-dynamics of any model, the reference
// finite elements' Newton method (fem objects only; solver/newton_run.hpp), or the implicit
// steps' local/global iterations with the inertia relaxed (what integrator: implicit takes).
enum class StaticSolver { relaxation, newton, implicit };
// What dt: auto takes its share of: the Gershgorin bound on the shape-memory stiffness, or
// the highest frequency found by power iteration on the linearised forces (Simulator).
enum class DtEstimate { gershgorin, power };

struct SimulationSpec {
  std::optional<double> dt;  // s; nullopt = "auto"
  double dt_safety = 0.5;    // fraction of the stability limit used by dt: auto
  DtEstimate dt_estimate = DtEstimate::gershgorin;  // that limit's estimate
  double duration = 1.0;  // s (static: the schedules are evaluated at its end)
  Integrator integrator = Integrator::verlet;
  int implicit_iterations = 20;      // implicit: most global solves per step
  double implicit_tolerance = 1e-6;  // N, implicit: a step's largest residual nodal force
  SourceLoc integrator_loc;          // of `integrator`; line 0 when absent
  SolveMode mode = SolveMode::dynamic;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  // m/s^2
  double damping = 0.0;                               // 1/s, mass-proportional viscous damping
  double tolerance = 1e-6;        // N, static mode: largest residual nodal force
  long max_iterations = 1000000;  // static mode
  int load_steps = 1;             // static mode: equilibria at duration * k / load_steps
  Relaxation relaxation = Relaxation::kinetic;     // static mode: how energy is taken out
  bool relaxation_mass_scaling = true;             // static mode: fictitious masses (Simulator)
  StaticSolver solver = StaticSolver::relaxation;  // static mode
  SourceLoc solver_loc;                            // of `solver`; line 0 when absent
  // s, dynamics: nodes whose stability limit is below this get the inertia that lifts it to
  // this (mass scaling; gravity keeps the true masses). nullopt: none.
  std::optional<double> mass_scaling_dt;
  SourceLoc loc;
};

// `transform`: each point p becomes R(axis, angle) (scale * p) + translate (m).
struct MeshTransform {
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();  // each > 0: no mirror
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit
  double angle = 0.0;                               // rad, right-handed about axis
  Eigen::Vector3d translate = Eigen::Vector3d::Zero();
  bool identity() const {
    return scale == Eigen::Vector3d::Ones() && angle == 0.0 && translate.isZero(0.0);
  }
};

struct MeshSpec {
  std::string generator;              // "box", "ellipsoid", "cylinder"
  CellType element = CellType::hexa;  // box: hexa|tetra
  bool surface = false;               // ellipsoid/cylinder: closed surface instead of volume
  Eigen::Vector3d size = Eigen::Vector3d::Constant(0.01);   // box, m
  std::array<int, 3> cells{4, 4, 4};                        // box
  Eigen::Vector3d radii = Eigen::Vector3d::Constant(0.01);  // ellipsoid, m
  int subdivisions = 2;                                     // ellipsoid
  int layers = 3;                                           // ellipsoid volume
  int hexahedra = 0;  // ellipsoid volume: cells per axis of a mapped grid; 0: the shells
  double radius = 0.01, length = 0.02;               // cylinder, m
  int around = 16, along = 4, rings = 2;             // cylinder
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // m
  std::string file;                                  // instead of a generator
  std::string units = "m";                           // of the file's coordinates
  std::string component;            // a PML file: the component whose cells are the object's
  std::vector<int> labels;          // a label image's labels that make the object
  bool fill_tetra = false;          // a closed surface file filled with tetrahedra
  std::optional<double> fill_edge;  // m, their largest edge inside (with fill_tetra)
  std::optional<double> remesh;     // m: the file's surface remeshed to this edge
  MeshTransform transform;          // file or generated mesh, before remesh and fill
  // The mesh of `file` in metres, as the loader read it (scene_io.hpp): compiling reads no
  // file.
  std::shared_ptr<const Mesh> file_mesh;
  std::vector<std::string> file_notes;  // what reading it repaired (merged points, orientation)
  std::vector<int> atom_ids;            // a PML file: each node's atom index there (for LML loads)
  SourceLoc loc;
};

// How an elastic component resists deformation: the paper's local shape memory, or explicit
// finite elements (TLED: hexahedra with one point and hourglass control, or tetrahedra).
enum class ElasticModel { shape_memory, fem };
// The finite elements' law and the implicit solver's hexahedron are fem::Law (Neo-Hookean for
// TLED and Newton, linear for Newton only) and fem::HexaElement (fem.hpp).

struct MaterialSpec {
  ElasticModel model = ElasticModel::shape_memory;
  std::optional<double> stiffness;  // N/m, shape memory spring of each node
  // Pa, fem: compressible Neo-Hookean; shape memory: K calibrated from it (calibration.hpp)
  std::optional<double> young;
  std::optional<double> poisson;  // in (-1, 0.5): fem, or the FEM K is calibrated on
  int calibration_axis = 2;       // shape memory with young: the compression axis (0 x, 1 y, 2 z)
  SourceLoc young_loc;            // of `young`, for messages; line 0 when absent
  double hourglass = 0.3;         // fem hexahedra (TLED): hourglass over the shear stiffness
  fem::Law law = fem::Law::neo_hookean;                       // fem
  SourceLoc law_loc;                                          // of `law`; line 0 when absent
  fem::HexaElement hexa = fem::HexaElement::mean_dilatation;  // fem hexahedra, Newton only
  SourceLoc hexa_loc;                                         // of `hexa`; line 0 when absent
  std::optional<double> density;                              // kg/m^3 (volumetric meshes)
  std::optional<double> mass;  // kg, total, spread by lumped cell measure
  FrameMode frame = FrameMode::polar;
  bool reaction = true;  // apply -f/n to the neighbours (momentum kept)
  SourceLoc loc;
};

struct NodeSelector {
  enum class Kind { all, named, indices, box, sphere, half_space };
  Kind kind = Kind::all;
  std::string name;          // named: a node set of the generated mesh
  std::vector<int> indices;  // indices: from "0-3,7" or a list
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();  // box, m
  Eigen::Vector3d center = Eigen::Vector3d::Zero();                              // sphere, m
  double radius = 0.0;                                                           // sphere, m
  Eigen::Vector3d point = Eigen::Vector3d::Zero(),
                  normal = Eigen::Vector3d::UnitZ();  // half-space: (x - point).normal >= 0
  SourceLoc loc;
};

// What an object is, in the scene and in the model it compiles to (Component::kind).
enum class ObjectType { elastic, rigid, active };

struct MotionSpec {      // a driven rigid object
  Schedule translation;  // m
  Schedule rotation;     // rad, rotation vector
  SourceLoc loc;
};

struct FibreSpec {  // contractile fibres of an active object
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();
  double max_contraction = 0.0;     // ratio in (0, 1)
  std::optional<double> stiffness;  // N/m; the material's when absent
  Schedule activation;              // a(t) in x
  SourceLoc loc;
};

// A shape-memory object's K from a Young's modulus (scene `young`): calibrated on the object's
// own mesh against the reference FEM, by calibration::calibrate_object (calibration.hpp).
struct StiffnessCalibration {
  std::string component;
  double young = 0.0, poisson = 0.0;  // Pa, -: the FEM's material
  int axis = 2;                       // compression axis: 0 x, 1 y, 2 z
  double strain = 0.0;                // nominal compression of the extent along the axis
  double push = 0.0;                  // m
  int held = 0, pushed = 0;           // nodes clamped at either end
  double h = 0.0;                     // m, mean rest edge length
  double fem_force = 0.0;             // N, along the axis on the pushed nodes
  double stiffness = 0.0;             // N/m: the K whose force is fem_force
  double alpha = 0.0;                 // stiffness / (young h), beside `phymul calibrate`
  double displacement_rms = 0.0;      // rms over nodes of |u_lsm - u_fem|, over push
  double displacement_max = 0.0;      // largest |u_lsm - u_fem|, over push
  long lsm_iterations = 0;
  int fem_newton_iterations = 0;
};

struct ObjectSpec {
  std::string name;
  ObjectType type = ObjectType::elastic;
  MeshSpec mesh;
  MaterialSpec material;
  bool volume_constraint = false;  // keep the volume enclosed by its boundary surface
  Schedule target_volume;          // m^3 in x over time; empty: the rest volume

  std::optional<MotionSpec> motion;  // rigid: driven when given
  FibreSpec fibres;                  // active
  // Shape memory given `young`: the calibration that set material.stiffness (the loader's
  // calibrate_stiffness, calibration.hpp); compile_scene refuses `young` without it.
  std::optional<StiffnessCalibration> calibration;
  SourceLoc loc;
};

// Whether the object's calibration was made for its material as it stands (the same E, nu and
// axis): prepare_scene then keeps it and compile_scene uses its K.
inline bool calibration_current(const ObjectSpec& o) {
  const MaterialSpec& m = o.material;
  return o.calibration && o.calibration->young == m.young && o.calibration->poisson == m.poisson &&
         o.calibration->axis == m.calibration_axis;
}

// Coincident nodes of two objects: merged (stitches, Fig. 1a) or doubled (Fig. 1b).
struct LinkSpec {
  std::string object, with;
  NodeSelector nodes, with_nodes;
  double tolerance = 1e-6;  // m
  SourceLoc loc;
};

struct LoadSpec {  // applied nodal force, the same on every selected node
  std::string object;
  NodeSelector nodes;
  Schedule force;  // N per node
  SourceLoc loc;
};

struct ConstraintSpec {
  enum class Kind { fixed, displacement, spring };
  Kind kind = Kind::fixed;
  std::string object;
  NodeSelector nodes;
  std::array<bool, 3> axes{true, true, true};  // displacement: which axes are prescribed
  Schedule displacement;                       // m, from the rest position
  double stiffness = 0.0;                      // N/m, spring: of each node's spring
  SourceLoc loc;
};

// A follower pressure on the boundary faces of an object (loads with `type: pressure`).
struct PressureSpec {
  std::string object;
  NodeSelector nodes;  // the faces whose nodes are all selected
  bool in_cylinder = false;
  Eigen::Vector3d cylinder_point = Eigen::Vector3d::Zero();  // m
  Eigen::Vector3d cylinder_axis = Eigen::Vector3d::UnitZ();  // normalised
  double cylinder_radius = 0.0;                              // m
  Schedule pressure;                                         // Pa in x
  SourceLoc loc;
};

// The shape of a rigid obstacle, in the scene and in the model (RigidObstacle). plane: the
// half-space behind a point, opposite to its outward normal; sphere; capsule: the points within
// a radius of a segment, both ends rounded; probe: an endorectal probe, a capsule whose base end
// extends to infinity backwards (open there, rounded at the tip).
enum class ObstacleShape { plane, sphere, capsule, probe };

// A rigid analytic obstacle (top-level `obstacles:`); see RigidObstacle.
struct ObstacleSpec {
  using Shape = ObstacleShape;
  std::string name;  // monitors column; "" = obstacle<index>
  Shape shape = Shape::plane;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // m
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();     // normalised
  double radius = 0.0, length = 0.0;                   // m
  Schedule motion;                                     // m, translation
  bool keep_inside = false;
  std::vector<std::string> objects;  // empty: all
  std::vector<SourceLoc> object_locs;
  double friction = 0.0;
  SourceLoc loc;
};

// Two deformable objects in frictionless contact (top-level `contacts:`).
struct ContactSpec {
  std::array<std::string, 2> objects;
  SourceLoc loc;
};

// A tissue a needle may puncture, with its parameters (`needles[].tissues[]`).
struct NeedleTissueSpec {
  std::string object;
  double puncture_force = 0.0;  // N
  double friction = 0.0;        // N/m, along the shaft per inserted length
  double cutting_force = 0.0;   // N
  SourceLoc loc, object_loc;
};

// A point of an object that moves with it (`needles[].target`), whose distance to the tip
// is monitored.
struct NeedleTargetSpec {
  std::string object;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // m, at rest
  SourceLoc loc, object_loc;
};

// A straight rigid needle inserted along its axis (top-level `needles:`); see Needle.
struct NeedleSpec {
  std::string name;                                      // "" = needle<index>
  Eigen::Vector3d base = Eigen::Vector3d::Zero();        // m, the tip at depth 0
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // normalised
  Schedule depth;                                        // m in x
  double radius = 0.0005;                                // m
  double spacing = 0.001;                                // m
  std::vector<NeedleTissueSpec> tissues;
  std::optional<NeedleTargetSpec> target;
  SourceLoc loc;
};

// How a .vtu holds its numbers. `ascii`: text, each double in its shortest form that parses
// back to the same bits (readable, diffable, well-formed XML). `binary`: VTK XML appended
// raw data (UInt64 byte counts, little-endian), the same bits at a fraction of the time and
// size; ParaView, VTK and meshio read it, plain XML parsers do not (raw bytes are not XML).
enum class VtuEncoding { ascii, binary };

struct OutputSpec {
  double interval = 0.0;  // s between frames (dynamic); 0 = first and last frame only
  bool vtk = true;
  VtuEncoding format = VtuEncoding::ascii;
  SourceLoc loc;
};

// CamiTK LML loads (top-level `lml:`, docs/camitk.md): turned into loads, constraints and
// pressures of the objects read from a PML file when the scene is prepared, once.
struct LmlSpec {
  std::string file;  // relative to the scene file
  bool applied = false;
  SourceLoc loc;
};

struct Scene {
  std::filesystem::path file;
  SimulationSpec simulation;
  std::vector<ObjectSpec> objects;
  std::vector<LoadSpec> loads;
  std::vector<ConstraintSpec> constraints;
  std::vector<LinkSpec> stitches, doubled;
  std::vector<PressureSpec> pressures;
  std::vector<ObstacleSpec> obstacles;
  std::vector<ContactSpec> contacts;
  std::vector<NeedleSpec> needles;
  OutputSpec output;
  std::optional<LmlSpec> lml;
  std::vector<std::string> notes;  // what preparing it noticed that the objects' notes do not say
};

}  // namespace phymul
