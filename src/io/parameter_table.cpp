#include "io/parameter_table.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <stdexcept>

namespace phymul::io {

namespace {

Range gt(double min) { return {min, std::nullopt, true, false}; }
Range ge(double min) { return {min, std::nullopt, false, false}; }
Range closed(double min, double max) { return {min, max, false, false}; }
Range open_closed(double min, double max) { return {min, max, true, false}; }

const Condition kBox{"generator", {"box"}};
const Condition kEllipsoid{"generator", {"ellipsoid"}};
const Condition kCylinder{"generator", {"cylinder"}};
const Condition kRound{"generator", {"ellipsoid", "cylinder"}};
const Condition kShapeMemory{"model", {"shape-memory"}};
const Condition kFem{"model", {"fem"}};
const Condition kVolume{"surface", {"false"}};
const Condition kStatic{"mode", {"static"}};
const Condition kImplicit{"integrator", {"implicit"}};
const Condition kDisplacement{"type", {"displacement"}};
const Condition kSpring{"type", {"spring"}};
const Condition kRigid{"type", {"rigid"}};
const Condition kActive{"type", {"active"}};
const Condition kForce{"type", {"force"}};
const Condition kPressure{"type", {"pressure"}};
const Condition kVolumeKept{"volume_constraint", {"true"}};
const Condition kAxisShape{"shape", {"plane", "capsule", "probe"}};
const Condition kRoundShape{"shape", {"sphere", "capsule", "probe"}};
const Condition kCapsule{"shape", {"capsule"}};
const Condition kFill{"fill", {"tetra"}};

const std::vector<Section>& sections() {
  static const std::vector<Section> table{
      {"scene", "(top level)", "The keys at the top of a scene file. Only `objects` is required."},
      {"simulation", "simulation", "Time stepping and solver settings."},
      {"object", "objects[]", "Each entry of `objects`: one deformable body."},
      {"mesh", "objects[].mesh",
       "The mesh of an object: generated (`generator`) or read from a file (`file`). A file's "
       "mesh is scaled to metres (`units`), placed (`transform`), remeshed (`remesh`), then "
       "filled (`fill`), in that order."},
      {"transform", "objects[].mesh.transform",
       "Places the mesh (file or generated) in the scene's frame, so that organs segmented from "
       "one image sit where they belong: each point p becomes R (S p) + t, scale first, then "
       "the rotation, then the translation. A mirror is refused (every scale > 0): it would "
       "turn the cells inside out; a change of axes such as LPS to RAS is a rotation (180 deg "
       "about z)."},
      {"rotation", "objects[].mesh.transform.rotate",
       "A rotation by `angle` about `axis` through the origin, right-handed (counterclockwise "
       "seen from the axis tip): 90 deg about [0, 0, 1] takes x to y."},
      {"material", "objects[].material",
       "Shape-memory material of an object. Give its `density` or its total `mass`."},
      {"load", "loads[]",
       "Each entry of `loads`: a nodal force, the same on every selected node, or a pressure on "
       "boundary faces."},
      {"constraint", "constraints[]",
       "Each entry of `constraints`: nodes held in place or moved by a prescribed displacement."},
      {"schedule", "schedule[]",
       "Each event of `loads[].schedule`, `constraints[].schedule` and `obstacles[].motion`. "
       "Values are linear between "
       "events, held before the first and after the last."},
      {"pressure_cylinder", "loads[].cylinder",
       "The faces of a pressure load whose rest centroid lies within `radius` of an infinite "
       "line (the paper's cylinder-shaped endorectal-probe pressure)."},
      {"scalar_schedule", "scalar_schedule[]",
       "Each event of `loads[].pressure_schedule` and `objects[].target_volume`: a single "
       "quantity in the unit of the scheduled field. Linear between events, held before the "
       "first and after the last."},
      {"obstacle", "obstacles[]",
       "Each entry of `obstacles`: a rigid analytic shape the nodes may not enter (or, with "
       "`keep_inside`, may not leave), enforced by projection after the prescribed "
       "displacements and before the volume constraints."},
      {"contact", "contacts[]",
       "Each entry of `contacts`: two deformable objects that may touch but not interpenetrate "
       "(frictionless, node against surface triangle)."},
      {"needle", "needles[]",
       "Each entry of `needles`: a straight rigid needle pushed along its axis into the "
       "tissues it lists, in turn (docs/needles.md). Its tip presses a tissue's surface until "
       "the push exceeds that tissue's `puncture_force`; then the tissue the tip meets is held "
       "on the shaft, with friction along it. Dynamic mode only."},
      {"needle_tissue", "needles[].tissues[]",
       "A volume object the needle may puncture, with its own parameters."},
      {"needle_target", "needles[].target",
       "A point of an object, moving with it: monitors.csv gets its distance to the tip."},
      {"nodes", "nodes",
       "A node selector (`nodes:` of loads and constraints) is one of: omitted (all nodes), a "
       "node-set name of the generated mesh (`top`), an index list (`\"0-3,7\"`, `7`), a YAML "
       "list of indices (`[0, 1, 5]`), or a map naming exactly one of the shapes below."},
      {"box", "nodes.box", "Nodes inside an axis-aligned box."},
      {"sphere", "nodes.sphere", "Nodes inside a sphere."},
      {"half_space", "nodes.half_space", "Nodes x with (x - point) . normal >= 0."},
      {"output", "output", "What is written while the simulation runs."},
      {"motion", "objects[].motion",
       "A rigid object with `motion` is driven (an instrument, a held bone): its centre of mass "
       "follows `translation` and it turns by `rotation` about its rest centre of mass. "
       "`motion: {}` holds it in place. Without `motion` it moves freely under its loads."},
      {"fibres", "objects[].fibres",
       "Contractile fibres of an active object (muscle): the lines of its nodes along "
       "`direction`; each segment is a tension-only spring of rest length l0 (1 - a(t) "
       "max_contraction). The passive shape memory stays."},
      {"activation", "objects[].fibres.activation[]",
       "Each event of the activation a(t): linear between events, held after the last."},
      {"link", "stitches[], doubled[]",
       "Each entry of `stitches` merges coincident nodes of two objects into shared border "
       "nodes (paper, Fig. 1a); each entry of `doubled` keeps coincident nodes as two nodes held "
       "at one position and velocity (Fig. 1b). A node of `nodes` (of `object`) is paired with "
       "the nearest node of `with_nodes` (of `with`) within `tolerance`."},
  };
  return table;
}

std::vector<Parameter> scene_parameters() {
  return {
      {.section = "scene",
       .name = "simulation",
       .kind = Kind::map,
       .default_note = "defaults",
       .child = "simulation",
       .doc = "Time stepping and solver settings."},
      {.section = "scene",
       .name = "objects",
       .kind = Kind::list,
       .range = ge(1),
       .required = true,
       .child = "object",
       .doc = "The deformable bodies."},
      {.section = "scene",
       .name = "loads",
       .kind = Kind::list,
       .default_note = "none",
       .child = "load",
       .doc = "Applied nodal forces."},
      {.section = "scene",
       .name = "constraints",
       .kind = Kind::list,
       .default_note = "none",
       .child = "constraint",
       .doc = "Fixed and prescribed-displacement nodes."},
      {.section = "scene",
       .name = "stitches",
       .kind = Kind::list,
       .default_note = "none",
       .child = "link",
       .doc = "Objects sharing border nodes (merged coincident nodes)."},
      {.section = "scene",
       .name = "doubled",
       .kind = Kind::list,
       .default_note = "none",
       .child = "link",
       .doc = "Doubled nodes: pairs of coincident nodes held together."},
      {.section = "scene",
       .name = "obstacles",
       .kind = Kind::list,
       .default_note = "none",
       .child = "obstacle",
       .doc = "Rigid analytic shapes (planes, spheres, capsules, probes) in contact with the "
              "objects."},
      {.section = "scene",
       .name = "contacts",
       .kind = Kind::list,
       .default_note = "none",
       .child = "contact",
       .doc = "Pairs of objects in contact with each other (deformable, or one a driven rigid "
              "object)."},
      {.section = "scene",
       .name = "needles",
       .kind = Kind::list,
       .default_note = "none",
       .child = "needle",
       .doc = "Needles inserted into the objects (biopsy, brachytherapy)."},
      {.section = "scene",
       .name = "output",
       .kind = Kind::map,
       .default_note = "defaults",
       .child = "output",
       .doc = "Output settings."},
      {.section = "scene",
       .name = "lml",
       .kind = Kind::path,
       .default_note = "none",
       .doc = "CamiTK LML loads (docs/camitk.md), relative to the scene file: their atom indices "
              "are those of the PML file the objects' meshes come from. Translation: the nodes' "
              "displacement on the axes its direction gives (`NULL`: held at 0; all three held "
              "at 0: fixed nodes); Force: a nodal force; Pressure: a pressure on the boundary "
              "faces whose nodes are all loaded. Units: mm, microm, nm; N, kN, pN; kPa, mmHg "
              "(or SI)."},
  };
}

std::vector<Parameter> simulation_parameters() {
  return {
      {.section = "simulation",
       .name = "dt",
       .kind = Kind::quantity,
       .dimension = Dimension::time,
       .range = gt(0),
       .keyword = "auto",
       .doc = "Time step; `auto` takes dt_safety times the stability limit.",
       .lands = lands(&SimulationSpec::dt)},
      {.section = "simulation",
       .name = "dt_safety",
       .kind = Kind::quantity,
       .range = open_closed(0, 1),
       .doc = "Fraction of the stability limit used by `dt: auto`.",
       .lands = lands(&SimulationSpec::dt_safety)},
      {.section = "simulation",
       .name = "dt_estimate",
       .kind = Kind::choice,
       .doc = "The stability limit `dt: auto` takes its share of: `gershgorin`, a bound on the "
              "shape-memory stiffness per node (cheap, pessimistic); `power`, 2/omega from the "
              "highest frequency of the forces linearised at the start, over the node inertias "
              "(power iteration, up to 800 force passes at set-up; nearer the true limit, so "
              "keep dt_safety below 1).",
       .lands = lands(&SimulationSpec::dt_estimate)},
      {.section = "simulation",
       .name = "mass_scaling_dt",
       .kind = Kind::quantity,
       .dimension = Dimension::time,
       .range = gt(0),
       .default_note = "none",
       .doc = "Dynamics: nodes whose stability limit is below this get the inertia that lifts it "
              "to this (mass scaling; gravity keeps the true masses).",
       .lands = lands(&SimulationSpec::mass_scaling_dt)},
      {.section = "simulation",
       .name = "duration",
       .kind = Kind::quantity,
       .dimension = Dimension::time,
       .range = gt(0),
       .doc = "Simulated time; static mode evaluates the schedules at its end.",
       .lands = lands(&SimulationSpec::duration)},
      {.section = "simulation",
       .name = "integrator",
       .kind = Kind::choice,
       .doc = "Time integration scheme. `verlet` and `newton-cotes` are explicit (dt below the "
              "stability limit); `implicit` is backward Euler solved by local/global iterations "
              "(rotations fitted per node, then one prefactorised sparse solve), stable at any "
              "dt, for elastic shape-memory, finite-element, active and rigid objects with "
              "gravity, forces, pressures, fixed and prescribed nodes, springs, stitches, doubled "
              "nodes, volume constraints, contacts, obstacles with Coulomb friction or not, and "
              "needles (see docs/implicit.md). "
              "Static mode relaxes with Verlet pseudo-dynamics unless `solver: implicit`.",
       .lands = lands(&SimulationSpec::integrator)},
      {.section = "simulation",
       .name = "implicit_iterations",
       .kind = Kind::integer,
       .range = closed(1, 100000),
       .when = {kImplicit},
       .doc = "Implicit steps: most global solves per step; the step ends there even when the "
              "residual is above `implicit_tolerance`.",
       .lands = lands(&SimulationSpec::implicit_iterations)},
      {.section = "simulation",
       .name = "implicit_tolerance",
       .kind = Kind::quantity,
       .dimension = Dimension::force,
       .range = gt(0),
       .when = {kImplicit},
       .doc = "Implicit steps: a step's iterations stop when the largest residual nodal force "
              "of backward Euler (inertia, damping, every force, less the volume constraints' "
              "pressures) is below it.",
       .lands = lands(&SimulationSpec::implicit_tolerance)},
      {.section = "simulation",
       .name = "mode",
       .kind = Kind::choice,
       .doc = "`dynamic`: motion over time; `static`: equilibria (by damped relaxation or Newton, "
              "see `solver`).",
       .lands = lands(&SimulationSpec::mode)},
      {.section = "simulation",
       .name = "gravity",
       .kind = Kind::vector,
       .dimension = Dimension::acceleration,
       .doc = "Gravitational acceleration.",
       .lands = lands(&SimulationSpec::gravity)},
      {.section = "simulation",
       .name = "damping",
       .kind = Kind::quantity,
       .dimension = Dimension::rate,
       .range = ge(0),
       .doc = "Mass-proportional viscous damping.",
       .lands = lands(&SimulationSpec::damping)},
      {.section = "simulation",
       .name = "tolerance",
       .kind = Kind::quantity,
       .dimension = Dimension::force,
       .range = gt(0),
       .doc = "Static mode: converged when the largest residual nodal force is below it.",
       .lands = lands(&SimulationSpec::tolerance)},
      {.section = "simulation",
       .name = "max_iterations",
       .kind = Kind::integer,
       .range = ge(1),
       .doc = "Static mode: iteration limit.",
       .lands = lands(&SimulationSpec::max_iterations)},
      {.section = "simulation",
       .name = "load_steps",
       .kind = Kind::integer,
       .range = closed(1, 1e6),
       .doc = "Static mode: equilibria at duration * k / load_steps, k = 1..load_steps.",
       .lands = lands(&SimulationSpec::load_steps)},
      {.section = "simulation",
       .name = "relaxation",
       .kind = Kind::choice,
       .doc = "Static mode: how the pseudo-dynamics loses energy. kinetic: velocities zeroed "
              "at kinetic-energy peaks; fire: turned towards the force and zeroed when going "
              "uphill (Bitzek et al. 2006), about twice as fast without contacts, but it can "
              "stall on them; viscous: only the scene's damping.",
       .lands = lands(&SimulationSpec::relaxation)},
      {.section = "simulation",
       .name = "solver",
       .kind = Kind::choice,
       .when = {kStatic},
       .doc = "Static mode: `relaxation` (damped pseudo-dynamics, any model), `implicit` (backward-"
              "Euler steps of 1000 times dt from rest, each solved by the implicit integrator's "
              "local/global iterations to `tolerance` or 20 solves, until the residual is below "
              "`tolerance`; the implicit integrator's objects and loads) or `newton` (the "
              "reference finite elements: fully integrated hexahedra with mean dilatation or "
              "tetrahedra, Newton with a line search and a sparse Cholesky, `load_steps` "
              "scaling the end-time loads). Newton takes `model: fem` objects, stitches, "
              "gravity, `force` loads, `fixed` and `displacement` constraints; it converges "
              "when the largest residual is below `tolerance` and 1e-10 of the loads; "
              "`max_iterations`, `relaxation`, `dt` and `damping` do not apply to it.",
       .lands = lands(&SimulationSpec::solver)},
  };
}

std::vector<Parameter> object_parameters() {
  return {
      {.section = "object",
       .name = "name",
       .kind = Kind::name,
       .required = true,
       .doc = "Unique name (letters, digits, `_`, `-`); loads and constraints refer to it.",
       .lands = lands(&ObjectSpec::name),
       .editable = false},
      {.section = "object",
       .name = "type",
       .kind = Kind::choice,
       .doc = "`elastic`: shape memory; `rigid`: one rigid body (bone, instrument); `active`: "
              "elastic with contractile fibres (muscle).",
       .lands = lands(&ObjectSpec::type),
       .editable = false},
      {.section = "object",
       .name = "mesh",
       .kind = Kind::map,
       .required = true,
       .child = "mesh",
       .doc = "The mesh, generated or read from a file."},
      {.section = "object",
       .name = "material",
       .kind = Kind::map,
       .required = true,
       .child = "material",
       .doc = "The material."},
      {.section = "object",
       .name = "volume_constraint",
       .kind = Kind::boolean,
       .doc = "Keep the volume enclosed by the boundary surface (elastic and active objects).",
       .lands = lands(&ObjectSpec::volume_constraint)},
      {.section = "object",
       .name = "target_volume",
       .kind = Kind::scalar_schedule,
       .dimension = Dimension::volume,
       .range = gt(0),
       .default_note = "the rest volume",
       .when = {kVolumeKept},
       .doc = "Enclosed volume to keep: a constant, or a list of {t, value} events (bladder "
              "filling).",
       .lands = lands(&ObjectSpec::target_volume)},
      {.section = "object",
       .name = "motion",
       .kind = Kind::map,
       .default_note = "free",
       .when = {kRigid},
       .child = "motion",
       .doc = "Drives a rigid object."},
      {.section = "object",
       .name = "fibres",
       .kind = Kind::map,
       .required = true,
       .when = {kActive},
       .child = "fibres",
       .doc = "The contractile fibres of an active object."},
  };
}

std::vector<Parameter> mesh_parameters() {
  return {
      {.section = "mesh",
       .name = "generator",
       .kind = Kind::choice,
       .choices = {"box", "ellipsoid", "cylinder"},
       .one_of = "source",
       .doc = "Which mesh generator builds the object.",
       .lands = lands(&MeshSpec::generator),
       .editable = false},
      {.section = "mesh",
       .name = "file",
       .kind = Kind::path,
       .one_of = "source",
       .doc = "A mesh file, relative to the scene file: legacy VTK ASCII unstructured grid "
              "(`.vtk`; triangle, quad, tetra, hexahedron, wedge cells), VTK XML unstructured "
              "grid (`.vtu`: ASCII, base64 or appended arrays, plain or zlib-compressed, the same "
              "cells) or Gmsh ASCII 4.1 or 2.2 (`.msh`; the highest-dimension elements are the "
              "cells, physical groups become node sets). All volume or all surface cells. Or a "
              "closed surface: STL (ASCII or binary), OBJ, PLY (ASCII or binary) or VTK XML "
              "PolyData (`.vtp`, its polygons), checked closed, manifold and free of crossing "
              "triangles, its orientation made outward. Or a CamiTK PML physical model (`.pml`, "
              "docs/camitk.md), one of its components (`component`). Or a label image (a "
              "segmentation): NIfTI-1, `.nii` or `.nii.gz`, with `labels` and `fill`; its "
              "chosen labels become a smooth closed surface in the image's physical frame "
              "(docs/anatomy.md), then tetrahedra.",
       .lands = lands(&MeshSpec::file),
       .editable = false},
      {.section = "mesh",
       .name = "component",
       .kind = Kind::text,
       .default_note = "the only exclusive component with cells",
       .doc = "A CamiTK PML `file` (docs/camitk.md): the exclusive component (structural or "
              "multi) whose cells are the object's; its atoms become the nodes, every "
              "informative component a node set (of the atoms it shares with them; characters "
              "other than letters, digits, '_' and '-' become '_' in its name).",
       .lands = lands(&MeshSpec::component),
       .editable = false},
      {.section = "mesh",
       .name = "labels",
       .kind = Kind::integers,
       .range = closed(-2147483648.0, 2147483647.0),
       .default_note = "required for a label image",
       .doc = "A label image `file` (`.nii`, `.nii.gz`): the labels whose voxels make the object "
              "(e.g. `[1, 2]`: a gland's two zones together).",
       .lands = lands(&MeshSpec::labels),
       .editable = false},
      {.section = "mesh",
       .name = "units",
       .kind = Kind::choice,
       .choices = {"m", "cm", "mm", "um"},
       .doc = "Length unit of the coordinates in `file`.",
       .lands = lands(&MeshSpec::units),
       .editable = false},
      {.section = "mesh",
       .name = "fill",
       .kind = Kind::choice,
       .choices = {"tetra"},
       .doc = "A closed surface read from `file` filled with tetrahedra (Gmsh's Delaunay "
              "mesher), its triangles kept as the boundary: the object is volumetric. Absent: "
              "the surface is the object."},
      {.section = "mesh",
       .name = "edge",
       .kind = Kind::quantity,
       .dimension = Dimension::length,
       .range = gt(0),
       .default_note = "required with `fill`",
       .when = {kFill},
       .doc = "With `fill` (required there): the largest edge of the tetrahedra inside; for a "
              "label image also the surface triangles' size.",
       .lands = lands(&MeshSpec::fill_edge),
       .editable = false},
      {.section = "mesh",
       .name = "remesh",
       .kind = Kind::quantity,
       .dimension = Dimension::length,
       .range = gt(0),
       .default_note = "none",
       .doc = "A closed surface read from `file` remeshed to triangles of about this edge "
              "(isotropic remeshing, docs/anatomy.md), after `transform` and before "
              "`fill`; `phymul check` reports its quality and deviation. Too long an edge for "
              "the surface (fewer than 20 triangles) is refused with the range.",
       .lands = lands(&MeshSpec::remesh),
       .editable = false},
      {.section = "mesh",
       .name = "transform",
       .kind = Kind::map,
       .default_note = "none",
       .child = "transform",
       .doc = "Scale, rotation and translation of the mesh."},
      {.section = "mesh",
       .name = "element",
       .kind = Kind::choice,
       .when = {kBox},
       .doc = "Box cells: hexahedra, or each hexahedron split into 6 tetrahedra.",
       .lands = lands(&MeshSpec::element)},
      {.section = "mesh",
       .name = "size",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .range = gt(0),
       .when = {kBox},
       .doc = "Box edge lengths along x, y, z.",
       .lands = lands(&MeshSpec::size)},
      {.section = "mesh",
       .name = "cells",
       .kind = Kind::integer_vector,
       .range = closed(1, 1000),
       .when = {kBox},
       .doc = "Box cells along x, y, z.",
       .lands = lands(&MeshSpec::cells)},
      {.section = "mesh",
       .name = "radii",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .range = gt(0),
       .when = {kEllipsoid},
       .doc = "Ellipsoid semi-axes along x, y, z.",
       .lands = lands(&MeshSpec::radii)},
      {.section = "mesh",
       .name = "subdivisions",
       .kind = Kind::integer,
       .range = closed(0, 7),
       .when = {kEllipsoid},
       .doc = "Icosahedron subdivisions: 20 * 4^s surface triangles.",
       .lands = lands(&MeshSpec::subdivisions)},
      {.section = "mesh",
       .name = "layers",
       .kind = Kind::integer,
       .range = closed(1, 100),
       .when = {kEllipsoid, kVolume},
       .doc = "Ellipsoid volume: concentric shells from the centre to the surface.",
       .lands = lands(&MeshSpec::layers)},
      {.section = "mesh",
       .name = "hexahedra",
       .kind = Kind::integer,
       .range = closed(0, 100),
       .when = {kEllipsoid, kVolume},
       .doc = "Ellipsoid volume: instead of shells, a grid of this many hexahedra per axis "
              "(even) mapped from a cube onto the ellipsoid; cells of nearly one size, so a "
              "larger stable time step. 0: the shells.",
       .lands = lands(&MeshSpec::hexahedra)},
      {.section = "mesh",
       .name = "radius",
       .kind = Kind::quantity,
       .dimension = Dimension::length,
       .range = gt(0),
       .when = {kCylinder},
       .doc = "Cylinder radius.",
       .lands = lands(&MeshSpec::radius)},
      {.section = "mesh",
       .name = "length",
       .kind = Kind::quantity,
       .dimension = Dimension::length,
       .range = gt(0),
       .when = {kCylinder},
       .doc = "Cylinder length along z.",
       .lands = lands(&MeshSpec::length)},
      {.section = "mesh",
       .name = "around",
       .kind = Kind::integer,
       .range = closed(3, 1000),
       .when = {kCylinder},
       .doc = "Cylinder nodes per ring.",
       .lands = lands(&MeshSpec::around)},
      {.section = "mesh",
       .name = "along",
       .kind = Kind::integer,
       .range = closed(1, 1000),
       .when = {kCylinder},
       .doc = "Cylinder cell layers along z.",
       .lands = lands(&MeshSpec::along)},
      {.section = "mesh",
       .name = "rings",
       .kind = Kind::integer,
       .range = closed(1, 100),
       .when = {kCylinder, kVolume},
       .doc = "Cylinder volume: rings of the triangulated disk extruded along z.",
       .lands = lands(&MeshSpec::rings)},
      {.section = "mesh",
       .name = "surface",
       .kind = Kind::boolean,
       .when = {kRound},
       .doc = "Generate a closed surface mesh instead of a volume mesh.",
       .lands = lands(&MeshSpec::surface)},
      {.section = "mesh",
       .name = "center",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .doc = "Centre of the generated mesh.",
       .lands = lands(&MeshSpec::center)},
  };
}

std::vector<Parameter> transform_parameters() {
  return {
      {.section = "transform",
       .name = "scale",
       .kind = Kind::vector,
       .range = gt(0),
       .uniform = true,
       .doc = "Scale factors along x, y, z, or one for all three; applied first.",
       .lands = lands(&MeshTransform::scale),
       .editable = false},
      {.section = "transform",
       .name = "rotate",
       .kind = Kind::map,
       .default_note = "none",
       .child = "rotation",
       .doc = "Rotation, applied after the scale."},
      {.section = "transform",
       .name = "translate",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .doc = "Translation, applied last.",
       .lands = lands(&MeshTransform::translate),
       .editable = false},
      {.section = "rotation",
       .name = "axis",
       .kind = Kind::vector,
       .required = true,
       .doc = "Rotation axis; any non-zero length."},
      {.section = "rotation",
       .name = "angle",
       .kind = Kind::quantity,
       .dimension = Dimension::angle,
       .required = true,
       .doc = "Rotation angle (`30 deg`, or radians without a unit).",
       .lands = lands(&MeshTransform::angle),
       .editable = false},
  };
}

std::vector<Parameter> material_parameters() {
  return {
      {.section = "material",
       .name = "model",
       .kind = Kind::choice,
       .doc = "Elasticity: the paper's local shape memory, or explicit finite elements (TLED: "
              "compressible Neo-Hookean; hexahedra with one point and hourglass control, or "
              "tetrahedra, with wedges cut into three tetrahedra each; with `solver: newton`, "
              "the same elements solved implicitly).",
       .lands = lands(&MaterialSpec::model),
       .editable = false},
      {.section = "material",
       .name = "stiffness",
       .kind = Kind::quantity,
       .dimension = Dimension::stiffness,
       .range = gt(0),
       .default_note = "required for shape-memory elastic and active objects, unless `young` "
                       "is given",
       .when = {kShapeMemory},
       .doc = "Shape-memory spring of each node.",
       .lands = lands(&MaterialSpec::stiffness)},
      {.section = "material",
       .name = "young",
       .kind = Kind::quantity,
       .dimension = Dimension::pressure,
       .range = gt(0),
       .default_note = "required when `model` is `fem`",
       .doc = "Young's modulus. Finite elements: of their law. Shape memory (instead of "
              "`stiffness`, with `poisson`): K is calibrated on the object's own mesh, so that "
              "a 1 % compression along `calibration_axis`, both ends clamped, takes the force "
              "that finite elements of E and nu (linear law) take; `phymul check` prints K and "
              "how far the two displacement fields differ. The calibration holds for that load: "
              "in bending the shape memory can be 0.4-1.8 times as stiff (README).",
       .lands = lands(&MaterialSpec::young)},
      {.section = "material",
       .name = "poisson",
       .kind = Kind::quantity,
       .range = {-1.0, 0.5, true, true},
       .default_note = "required with `young`",
       .doc = "Poisson's ratio of the finite elements (for shape memory, of those its K is "
              "calibrated on); near 0.5 the explicit FEM's stable time step shrinks with the "
              "bulk wave speed.",
       .lands = lands(&MaterialSpec::poisson)},
      {.section = "material",
       .name = "calibration_axis",
       .kind = Kind::choice,
       .when = {kShapeMemory},
       .doc = "With `young`: the axis along which the object is compressed to calibrate K "
              "(clamped: the nodes within a quarter of the mean edge of either end, at least "
              "four).",
       .lands = lands(&MaterialSpec::calibration_axis, kAxisWords)},
      {.section = "material",
       .name = "hourglass",
       .kind = Kind::quantity,
       .range = closed(0.0, 1.0),
       .when = {kFem},
       .doc = "Hexahedra: hourglass stiffness as a fraction of the element's shear stiffness "
              "(TLED only: `solver: newton` integrates hexahedra fully and has no hourglass "
              "modes).",
       .lands = lands(&MaterialSpec::hourglass)},
      {.section = "material",
       .name = "law",
       .kind = Kind::choice,
       .when = {kFem},
       .doc = "Finite-element law: compressible Neo-Hookean (large deformation), or "
              "small-strain linear elasticity (`solver: newton` only).",
       .lands = lands(&MaterialSpec::law)},
      {.section = "material",
       .name = "hexa",
       .kind = Kind::choice,
       .when = {kFem},
       .doc = "`solver: newton` hexahedra: mean dilatation (Q1/P0, no locking near nu = 0.5), "
              "or Wilson's incompatible modes (CalculiX's C3D8I: bends exactly, a little stiffer "
              "near nu = 0.5, 4-6 times slower).",
       .lands = lands(&MaterialSpec::hexa)},
      {.section = "material",
       .name = "density",
       .kind = Kind::quantity,
       .dimension = Dimension::density,
       .range = gt(0),
       .one_of = "mass",
       .doc = "Mass density; volumetric meshes only.",
       .lands = lands(&MaterialSpec::density)},
      {.section = "material",
       .name = "mass",
       .kind = Kind::quantity,
       .dimension = Dimension::mass,
       .range = gt(0),
       .one_of = "mass",
       .doc = "Total mass, spread over the nodes by lumped cell measure.",
       .lands = lands(&MaterialSpec::mass)},
      {.section = "material",
       .name = "frame",
       .kind = Kind::choice,
       .when = {kShapeMemory},
       .doc = "How the local rotation of the rest shape is estimated.",
       .lands = lands(&MaterialSpec::frame)},
      {.section = "material",
       .name = "reaction",
       .kind = Kind::boolean,
       .when = {kShapeMemory},
       .doc = "Apply -f/n to the neighbours of each node, so that momentum is kept.",
       .lands = lands(&MaterialSpec::reaction)},
  };
}

std::vector<Parameter> load_parameters() {
  return {
      {.section = "load",
       .name = "type",
       .kind = Kind::choice,
       .choices = {"force", "pressure"},
       .required = true,
       .doc = "`force`: the same force on every selected node; `pressure`: a follower pressure "
              "on boundary faces, along minus their current outward normal."},
      {.section = "load",
       .name = "object",
       .kind = Kind::name,
       .required = true,
       .doc = "Name of the loaded object.",
       .lands = lands(&LoadSpec::object),
       .editable = false},
      {.section = "load",
       .name = "nodes",
       .kind = Kind::selector,
       .default_note = "all nodes",
       .doc = "The loaded nodes (node selector); for a pressure, the boundary faces whose nodes "
              "are all selected.",
       .lands = lands(&LoadSpec::nodes),
       .editable = false},
      {.section = "load",
       .name = "force",
       .kind = Kind::vector,
       .dimension = Dimension::force,
       .when = {kForce},
       .one_of = "value",
       .doc = "Constant force on each selected node.",
       .lands = lands(&LoadSpec::force)},
      {.section = "load",
       .name = "schedule",
       .kind = Kind::schedule,
       .dimension = Dimension::force,
       .when = {kForce},
       .one_of = "value",
       .doc = "Force on each selected node over time: a list of {t, value} events.",
       .lands = lands(&LoadSpec::force)},
      {.section = "load",
       .name = "pressure",
       .kind = Kind::quantity,
       .dimension = Dimension::pressure,
       .when = {kPressure},
       .one_of = "pressure",
       .doc = "Constant pressure; positive pushes into the body.",
       .lands = lands(&PressureSpec::pressure)},
      {.section = "load",
       .name = "pressure_schedule",
       .kind = Kind::scalar_schedule,
       .dimension = Dimension::pressure,
       .when = {kPressure},
       .one_of = "pressure",
       .doc = "Pressure over time: a list of {t, value} events (or a constant).",
       .lands = lands(&PressureSpec::pressure)},
      {.section = "load",
       .name = "cylinder",
       .kind = Kind::map,
       .default_note = "all faces",
       .when = {kPressure},
       .child = "pressure_cylinder",
       .doc = "Only the faces inside a cylinder (with `nodes`: the faces selected by both)."},
  };
}

std::vector<Parameter> constraint_parameters() {
  return {
      {.section = "constraint",
       .name = "type",
       .kind = Kind::choice,
       .required = true,
       .doc = "`fixed`: held at the rest position; `displacement`: moved as prescribed; "
              "`spring`: each node pulled back to its rest position by a linear spring (a "
              "compliant support: the soft tissue or ligaments around an organ).",
       .lands = lands(&ConstraintSpec::kind),
       .editable = false},
      {.section = "constraint",
       .name = "object",
       .kind = Kind::name,
       .required = true,
       .doc = "Name of the constrained object.",
       .lands = lands(&ConstraintSpec::object),
       .editable = false},
      {.section = "constraint",
       .name = "nodes",
       .kind = Kind::selector,
       .default_note = "all nodes",
       .doc = "The constrained nodes (node selector).",
       .lands = lands(&ConstraintSpec::nodes),
       .editable = false},
      {.section = "constraint",
       .name = "axes",
       .kind = Kind::axes,
       .when = {kDisplacement},
       .doc = "The prescribed axes: a non-empty combination of x, y, z.",
       .lands = lands(&ConstraintSpec::axes)},
      {.section = "constraint",
       .name = "displacement",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .when = {kDisplacement},
       .one_of = "value",
       .doc = "Constant displacement from the rest position.",
       .lands = lands(&ConstraintSpec::displacement)},
      {.section = "constraint",
       .name = "schedule",
       .kind = Kind::schedule,
       .dimension = Dimension::length,
       .when = {kDisplacement},
       .one_of = "value",
       .doc = "Displacement over time: a list of {t, value} events.",
       .lands = lands(&ConstraintSpec::displacement)},
      {.section = "constraint",
       .name = "stiffness",
       .kind = Kind::quantity,
       .dimension = Dimension::stiffness,
       .range = gt(0),
       .required = true,
       .when = {kSpring},
       .doc = "Stiffness of each node's spring. A layer of tissue of modulus E and thickness t "
              "over an area A holding n nodes: E A / (t n).",
       .lands = lands(&ConstraintSpec::stiffness)},
  };
}

std::vector<Parameter> schedule_parameters() {
  return {
      {.section = "schedule",
       .name = "t",
       .kind = Kind::quantity,
       .dimension = Dimension::time,
       .range = ge(0),
       .required = true,
       .doc = "Event time; strictly increasing along the schedule."},
      {.section = "schedule",
       .name = "value",
       .kind = Kind::vector,
       .required = true,
       .doc = "Value at t, in the unit of the scheduled field (N for a force, m for a "
              "displacement)."},
  };
}

std::vector<Parameter> selector_parameters() {
  return {
      {.section = "nodes",
       .name = "box",
       .kind = Kind::map,
       .one_of = "shape",
       .child = "box",
       .doc = "Axis-aligned box."},
      {.section = "nodes",
       .name = "sphere",
       .kind = Kind::map,
       .one_of = "shape",
       .child = "sphere",
       .doc = "Sphere."},
      {.section = "nodes",
       .name = "half_space",
       .kind = Kind::map,
       .one_of = "shape",
       .child = "half_space",
       .doc = "Half-space bounded by a plane."},
      {.section = "box",
       .name = "min",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .required = true,
       .doc = "Lower corner."},
      {.section = "box",
       .name = "max",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .required = true,
       .doc = "Upper corner, componentwise >= min."},
      {.section = "sphere",
       .name = "center",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .required = true,
       .doc = "Centre."},
      {.section = "sphere",
       .name = "radius",
       .kind = Kind::quantity,
       .dimension = Dimension::length,
       .range = gt(0),
       .required = true,
       .doc = "Radius."},
      {.section = "half_space",
       .name = "point",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .required = true,
       .doc = "A point on the plane."},
      {.section = "half_space",
       .name = "normal",
       .kind = Kind::vector,
       .required = true,
       .doc = "Direction into the selected side; any non-zero length, stored normalised."},
  };
}

std::vector<Parameter> component_parameters() {
  return {
      {.section = "motion",
       .name = "translation",
       .kind = Kind::schedule,
       .dimension = Dimension::length,
       .default_note = "none",
       .doc = "Displacement of the centre of mass over time.",
       .lands = lands(&MotionSpec::translation)},
      {.section = "motion",
       .name = "rotation",
       .kind = Kind::schedule,
       .default_note = "none",
       .doc = "Rotation vector (axis times angle, rad) over time, about the rest centre of "
              "mass.",
       .lands = lands(&MotionSpec::rotation)},
      {.section = "fibres",
       .name = "direction",
       .kind = Kind::vector,
       .required = true,
       .doc = "Direction of the fibres; any non-zero length."},
      {.section = "fibres",
       .name = "max_contraction",
       .kind = Kind::quantity,
       .range = {0.0, 1.0, true, true},
       .required = true,
       .doc = "Relative shortening of the fibre rest length at full activation.",
       .lands = lands(&FibreSpec::max_contraction)},
      {.section = "fibres",
       .name = "stiffness",
       .kind = Kind::quantity,
       .dimension = Dimension::stiffness,
       .range = gt(0),
       .default_note = "the material's stiffness",
       .doc = "Spring of each fibre segment.",
       .lands = lands(&FibreSpec::stiffness)},
      {.section = "fibres",
       .name = "activation",
       .kind = Kind::list,
       .range = ge(1),
       .required = true,
       .child = "activation",
       .doc = "The activation over time: a list of {t, a} events."},
      {.section = "activation",
       .name = "t",
       .kind = Kind::quantity,
       .dimension = Dimension::time,
       .range = ge(0),
       .required = true,
       .doc = "Event time; strictly increasing."},
      {.section = "activation",
       .name = "a",
       .kind = Kind::quantity,
       .range = closed(0, 1),
       .required = true,
       .doc = "Activation at t."},
      {.section = "link",
       .name = "object",
       .kind = Kind::name,
       .required = true,
       .doc = "The first object.",
       .lands = lands(&LinkSpec::object),
       .editable = false},
      {.section = "link",
       .name = "with",
       .kind = Kind::name,
       .required = true,
       .doc = "The second object.",
       .lands = lands(&LinkSpec::with),
       .editable = false},
      {.section = "link",
       .name = "nodes",
       .kind = Kind::selector,
       .default_note = "all nodes",
       .doc = "Nodes of `object` to pair; when given, each must find a partner.",
       .lands = lands(&LinkSpec::nodes),
       .editable = false},
      {.section = "link",
       .name = "with_nodes",
       .kind = Kind::selector,
       .default_note = "all nodes",
       .doc = "Nodes of `with` they may pair with.",
       .lands = lands(&LinkSpec::with_nodes),
       .editable = false},
      {.section = "link",
       .name = "tolerance",
       .kind = Kind::quantity,
       .dimension = Dimension::length,
       .range = gt(0),
       .doc = "Largest rest distance between paired nodes.",
       .lands = lands(&LinkSpec::tolerance)},
  };
}

std::vector<Parameter> interaction_parameters() {
  return {
      {.section = "pressure_cylinder",
       .name = "point",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .required = true,
       .doc = "A point of the cylinder's axis.",
       .lands = lands(&PressureSpec::cylinder_point),
       .editable = false},
      {.section = "pressure_cylinder",
       .name = "axis",
       .kind = Kind::vector,
       .required = true,
       .doc = "Direction of the axis; any non-zero length."},
      {.section = "pressure_cylinder",
       .name = "radius",
       .kind = Kind::quantity,
       .dimension = Dimension::length,
       .range = gt(0),
       .required = true,
       .doc = "Radius of the cylinder.",
       .lands = lands(&PressureSpec::cylinder_radius),
       .editable = false},
      {.section = "scalar_schedule",
       .name = "t",
       .kind = Kind::quantity,
       .dimension = Dimension::time,
       .range = ge(0),
       .required = true,
       .doc = "Event time; strictly increasing along the schedule."},
      {.section = "scalar_schedule",
       .name = "value",
       .kind = Kind::quantity,
       .required = true,
       .doc = "Value at t, in the unit of the scheduled field (Pa for a pressure, m^3 for a "
              "volume)."},
      {.section = "obstacle",
       .name = "name",
       .kind = Kind::name,
       .default_note = "`obstacle<index>`",
       .doc = "Name of the obstacle's contact-force columns in monitors.csv.",
       .lands = lands(&ObstacleSpec::name),
       .editable = false},
      {.section = "obstacle",
       .name = "shape",
       .kind = Kind::choice,
       .required = true,
       .doc = "`plane`: the half-space behind a plane; `sphere`; `capsule`: a segment with "
              "radius (both ends rounded); `probe`: a rounded cylinder (an endorectal probe), "
              "hemispherical tip, shaft without end behind it.",
       .lands = lands(&ObstacleSpec::shape),
       .editable = false},
      {.section = "obstacle",
       .name = "position",
       .kind = Kind::vector,
       .dimension = Dimension::length,
       .required = true,
       .doc = "At t = 0: a point of the plane; the sphere's centre; the capsule's first end "
              "centre; the centre of the probe's tip.",
       .lands = lands(&ObstacleSpec::position)},
      {.section = "obstacle",
       .name = "axis",
       .kind = Kind::vector,
       .required = true,
       .when = {kAxisShape},
       .doc = "Plane: its normal, towards the free side; capsule: from the first end to the "
              "second; probe: the direction it points to (from shaft to tip). Any non-zero "
              "length."},
      {.section = "obstacle",
       .name = "radius",
       .kind = Kind::quantity,
       .dimension = Dimension::length,
       .range = gt(0),
       .required = true,
       .when = {kRoundShape},
       .doc = "Radius of the sphere, capsule or probe.",
       .lands = lands(&ObstacleSpec::radius)},
      {.section = "obstacle",
       .name = "length",
       .kind = Kind::quantity,
       .dimension = Dimension::length,
       .range = ge(0),
       .required = true,
       .when = {kCapsule},
       .doc = "Distance between the centres of the capsule's two ends.",
       .lands = lands(&ObstacleSpec::length)},
      {.section = "obstacle",
       .name = "motion",
       .kind = Kind::schedule,
       .dimension = Dimension::length,
       .default_note = "fixed",
       .doc = "Translation of the shape from its position over time: a list of {t, value} "
              "events.",
       .lands = lands(&ObstacleSpec::motion)},
      {.section = "obstacle",
       .name = "keep_inside",
       .kind = Kind::boolean,
       .doc = "A container instead of an obstacle: the nodes may not leave the shape.",
       .lands = lands(&ObstacleSpec::keep_inside)},
      {.section = "obstacle",
       .name = "objects",
       .kind = Kind::names,
       .range = ge(1),
       .default_note = "all objects",
       .doc = "Names of the objects whose nodes it acts on."},
      {.section = "obstacle",
       .name = "friction",
       .kind = Kind::quantity,
       .range = ge(0),
       .doc = "Coulomb friction coefficient between the shape and the nodes.",
       .lands = lands(&ObstacleSpec::friction)},
      {.section = "contact",
       .name = "objects",
       .kind = Kind::names,
       .range = closed(2, 2),
       .required = true,
       .doc = "The two objects in contact (distinct; a rigid one must be driven: `motion:`)."},
  };
}

std::vector<Parameter> output_parameters() {
  return {
      {.section = "output",
       .name = "interval",
       .kind = Kind::quantity,
       .dimension = Dimension::time,
       .range = ge(0),
       .doc = "Time between frames (dynamic mode); 0 writes the first and last frame only.",
       .lands = lands(&OutputSpec::interval)},
      {.section = "output",
       .name = "vtk",
       .kind = Kind::boolean,
       .doc = "Write VTK files.",
       .lands = lands(&OutputSpec::vtk)},
      {.section = "output",
       .name = "format",
       .kind = Kind::choice,
       .doc = "How the .vtu frames hold their numbers. `ascii`: text, every double in its "
              "shortest form that reads back to the same bits (well-formed XML, diffable). "
              "`binary`: VTK XML appended raw data, the same bits written several times faster "
              "(README, Output); ParaView, VTK and meshio read it, plain XML parsers do not.",
       .lands = lands(&OutputSpec::format)},
  };
}

[[noreturn]] void table_error(const Parameter& p, std::string_view problem) {
  throw std::logic_error(
      fmt::format("parameter table: '{}' in '{}' {}", p.name, p.section, problem));
}

// A field that lands in a Spec takes its choices and its default from there: declared once.
void take_landing_defaults(Parameter& p) {
  if (!p.lands.member.has_value()) return;
  if (!p.default_value.empty()) table_error(p, "gives a default beside its Spec's");
  if (!p.lands.words.empty()) {
    if (!p.choices.empty()) table_error(p, "lists choices beside its Spec's words");
    p.choices = p.lands.words;
  }
  if (p.required || !p.one_of.empty() || !p.default_note.empty()) return;
  if (p.lands.default_text)
    p.default_value = *p.lands.default_text;
  else if (!p.keyword.empty())
    p.default_value = std::string(p.keyword);
  else
    table_error(p, "has no default in its Spec and no note saying what absence means");
}

const std::vector<Parameter>& parameters() {
  static const std::vector<Parameter> table = [] {
    std::vector<Parameter> all;
    for (auto part :
         {scene_parameters(), simulation_parameters(), object_parameters(), mesh_parameters(),
          transform_parameters(), material_parameters(), load_parameters(), constraint_parameters(),
          schedule_parameters(), selector_parameters(), interaction_parameters(),
          needle_parameters(), output_parameters(), component_parameters()})
      all.insert(all.end(), part.begin(), part.end());
    for (auto& parameter : all) take_landing_defaults(parameter);
    return all;
  }();
  return table;
}

}  // namespace

std::string Range::violation(double value, Dimension dimension) const {
  if (min && (min_open ? !(value > *min) : !(value >= *min)))
    return fmt::format("{} {}", min_open ? ">" : ">=", format_si(*min, dimension));
  if (max && (max_open ? !(value < *max) : !(value <= *max)))
    return fmt::format("{} {}", max_open ? "<" : "<=", format_si(*max, dimension));
  return {};
}

std::string Range::str() const {
  if (min && max)
    return fmt::format("{}{}, {}{}", min_open ? '(' : '[', *min, *max, max_open ? ')' : ']');
  if (min) return fmt::format("{} {}", min_open ? ">" : ">=", *min);
  if (max) return fmt::format("{} {}", max_open ? "<" : "<=", *max);
  return {};
}

std::span<const Section> section_table() { return sections(); }
std::span<const Parameter> parameter_table() { return parameters(); }

const Section* find_section(std::string_view name) {
  for (const auto& section : sections())
    if (section.name == name) return &section;
  return nullptr;
}

const Parameter* find_parameter(std::string_view section, std::string_view name) {
  for (const auto& parameter : parameters())
    if (parameter.section == section && parameter.name == name) return &parameter;
  return nullptr;
}

std::vector<const Parameter*> section_parameters(std::string_view section) {
  std::vector<const Parameter*> out;
  for (const auto& parameter : parameters())
    if (parameter.section == section) out.push_back(&parameter);
  return out;
}

namespace {

// Each kind's word for programs (SceneField::kind) and its wording in the reference.
struct KindNames {
  Kind kind;
  std::string_view word, name;
};
constexpr KindNames kKindNames[] = {
    {Kind::quantity, "quantity", "quantity"},
    {Kind::vector, "vector", "vector"},
    {Kind::integer, "integer", "integer"},
    {Kind::integer_vector, "integer_vector", "3 integers"},
    {Kind::integers, "integers", "list of whole numbers"},
    {Kind::boolean, "boolean", "boolean"},
    {Kind::choice, "choice", "enum"},
    {Kind::name, "name", "name"},
    {Kind::axes, "axes", "axes"},
    {Kind::selector, "selector", "node selector"},
    {Kind::schedule, "schedule", "schedule"},
    {Kind::scalar_schedule, "scalar_schedule", "scalar schedule"},
    {Kind::names, "names", "list of names"},
    {Kind::list, "list", "list of maps"},
    {Kind::map, "map", "map"},
    {Kind::path, "path", "file path"},
    {Kind::text, "text", "text"},
};

const KindNames& names_of(Kind kind) {
  for (const KindNames& k : kKindNames)
    if (k.kind == kind) return k;
  throw std::logic_error("a parameter kind without its names");
}

}  // namespace

std::string_view kind_name(Kind kind) { return names_of(kind).name; }
std::string_view kind_word(Kind kind) { return names_of(kind).word; }

}  // namespace phymul::io
