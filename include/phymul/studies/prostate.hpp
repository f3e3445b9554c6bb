// The prostate study (the paper's section 4, DESIGN 7): an endorectal probe pushes the
// prostate upward; the bladder above it, stitched to it, is nearly empty or full.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "phymul/model.hpp"

namespace phymul::prostate {

enum class Probe { pressure, rigid };
const char* probe_name(Probe probe);

// Which organ's nodes choose the stitches of the bladder neck: each takes the nearest node
// of the other organ, so the coarser organ chooses (two nodes may not take one partner).
enum class Neck {
  bladder,   // the bladder's bottom node and the ring of its neighbours
  prostate,  // the prostate's base nodes within stitch_radius of its axis
};

// What holds the prostate up besides the probe.
enum class Support {
  lateral,  // its lateral sides held rigidly (the endopelvic fascia on the levator ani)
  bladder,  // the paper's: only the bladder's top node is fixed, the prostate hangs from the
            // neck, and the two organs touch beyond it (a frictionless contact pair)
};
const char* support_name(Support support);

// Every quantity in SI; README "The prostate study" gives the source of each default.
struct Options {
  std::vector<double> fillings{50e-6, 100e-6, 200e-6, 300e-6, 400e-6};  // m^3 of urine
  std::vector<Probe> probes{Probe::pressure, Probe::rigid};
  // Prostate: a deformed sphere, volumetric, 4 x 3 x 3 cm (lateral, antero-posterior,
  // cranio-caudal = height, along z).
  Vec3 prostate_radii{0.020, 0.015, 0.015};  // m
  double prostate_density = 1050.0;          // kg/m^3
  ElasticModel prostate_model = ElasticModel::shape_memory;
  double prostate_stiffness = 640.0;  // N/m, shape memory K
  double prostate_young = 20e3;       // Pa, finite elements
  double prostate_poisson = 0.45;     // finite elements (linear tetrahedra)
  int prostate_hexahedra = 4;         // per axis, a grid mapped onto the ellipsoid
  Support support = Support::lateral;
  // N/m per node, Support::bladder: the lateral nodes (as Support::lateral holds them) on
  // springs to their rest positions instead, the soft tissue around the gland (0: none).
  double support_stiffness = 0.0;
  double anchor_fraction = 0.85;  // Support::lateral: nodes beyond this share of the half-width
  // Bladder: a surfacic sphere holding the filling, shaped by gravity from its top node.
  double bladder_wall_mass = 0.040;   // kg
  double urine_density = 1015.0;      // kg/m^3
  double bladder_stiffness = 5700.0;  // N/m, shape memory K of the wall
  int bladder_subdivisions = 3;       // of the icosahedron: 642 nodes
  Neck neck = Neck::prostate;
  double stitch_radius = 0.008;     // m, Neck::prostate: base nodes this close to its axis
  double stitch_tolerance = 0.006;  // m: each stitched node's partner lies within this
  // Probe under the prostate, along y (the rectum's direction in this simplified frame).
  double probe_radius = 0.010;  // m, a transrectal probe is about 2 cm across
  double probe_force = 2.0;     // N, pressure probe: the force its pressure adds up to
  double probe_indent = 0.005;  // m: it presses the faces within a probe sunk this deep
  double probe_lift = 0.004;    // m, rigid probe: how far it rises after touching
  double gravity = 9.81;        // m/s^2, along -z
  double damping = 20.0;        // 1/s (dynamic scenes only)
  // Dynamic scenes: dt = this share of the stability limit, estimated by power iteration on
  // the linearised forces (README "The prostate study", "Real time": the runs blow up 0.5 %
  // above that limit, and their highest frequency moves by 0.2 % along them).
  double dt_safety = 0.9;
  DtEstimate dt_estimate = DtEstimate::power;
  // s, dynamic scenes: mass scaling lifts the light nodes' stability limit to this (0: none).
  double mass_scaling_dt = 0.0;
  double tolerance = 1e-6;  // N, static equilibrium: largest residual nodal force
  // Static equilibria by relaxation (below), or by the implicit static solver.
  StaticSolver static_solver = StaticSolver::relaxation;
  // How the relaxation takes energy out: FIRE turns the motion downhill, where kinetic
  // damping only restarts at energy peaks and crawls along the hanging organs' soft modes
  // (docs/validation.md, "The paper's configuration").
  Relaxation relaxation = Relaxation::fire;
  // N, the same with the rigid probe or hanging organs, which stall short of 1e-6 N (a node
  // on an obstacle or a contact pair and on a kept volume's surface; docs/validation.md).
  // 1e-4 N left the hanging prostate up to 0.13 % of its height from its equilibrium.
  double contact_tolerance = 1e-5;
  int load_steps = 4;  // the probe's load in this many equilibria
};

// The study on the coarse bladder that runs faster than real time on one core (README "The
// prostate study"): icosphere 2 (162 nodes), so the neck's six stitches are chosen by the
// bladder, within 8 mm; the prostate grid's 8 corner nodes mass-scaled to a 250 us limit
// (+0.75 % of its mass). Its results differ from the fine bladder's by more than the
// filling's effect (README, mesh table).
Options coarse_bladder(Options options);

// What one scene of the study is: a filling, a probe and how the scene is run.
struct SceneSettings {
  double filling = 0.0;  // m^3
  Probe probe = Probe::pressure;
  bool dynamic = false;          // explicit dynamics (the real-time example) or static equilibria
  double duration = 1.0;         // s
  double settle_fraction = 0.2;  // the probe starts acting after this share of the duration
  int load_steps = 5;            // static: equilibria at duration * k / load_steps
  double pressure = 0.0;         // Pa, pressure probe
  Vec3 probe_axis_point = Vec3::Zero();  // m: cylinder axis point, or the rigid probe's tip
};

double bladder_radius(double filling);  // m, of the sphere holding `filling` (m^3)
std::string scene_text(const Options& options, const SceneSettings& settings);

// One filling, one probe: the state before (gravity alone) and after the probe.
struct FillingResult {
  double filling = 0.0;  // m^3, the target volume
  Probe probe = Probe::pressure;
  double bladder_volume = 0.0;            // m^3, enclosed at the end
  double prostate_height = 0.0;           // m, before the probe (top to bottom node)
  double prostate_deformation_pct = 0.0;  // height lost to the probe, % of that height
  double centre_displacement = 0.0;       // m, of the prostate's mean node position
  double probe_force = 0.0;          // N, upward, from the equilibrium of weights and held nodes
  double pressure_resultant = 0.0;   // N, pressure probe: its pressure summed on its faces
  double probe_contact_force = 0.0;  // N, rigid probe: upward, from its contact stage
  double centre_lift = 0.0;          // m, its upward part
  std::vector<int> stitched;         // global ids of the nodes both organs share
  int model_nodes = 0;
  long iterations = 0;  // of the static relaxation, all equilibria
  // Where the probe's upward force goes at the last equilibrium (N, z, upward on the
  // prostate positive): the bladder's pull at the neck (what balances the prostate's other
  // forces: its weight, the probe, the contact and its own holds), the bladder's push through
  // the contact beyond the neck, the prostate's lateral holds and the bladder's top node.
  double neck_force = 0.0, contact_force = 0.0, hold_force = 0.0, top_node_force = 0.0;
  std::vector<Vec3> before, after;  // node positions
};

// Node positions at a load time (s) of a static scene.
struct Frame {
  double time = 0.0;
  std::vector<Vec3> x;
};
using Frames = std::vector<Frame>;

// One of the study's scenes run in explicit dynamics on one thread, timed against the clock.
struct RealTimeRun {
  double filling = 0.0;  // m^3
  Probe probe = Probe::pressure;
  long steps = 0;
  double dt = 0.0;                // s
  double wall_time = 0.0;         // s, output included
  double real_time_factor = 0.0;  // steps x dt / wall time
  // steps x dt / the process's CPU time: what a step costs on one core when a busy machine
  // shares it (wall time then counts the waits too)
  double cpu_real_time_factor = 0.0;
  // steps x dt / the wall time inside the steps: the output and the set-up left out
  double stepping_real_time_factor = 0.0;
  double added_mass_pct = 0.0;  // mass scaling's added inertia, % of the model's mass
};

struct Study {
  Options options;
  std::vector<FillingResult> results;  // fillings in order, each probe in turn
  double wall_time = 0.0;              // s
  std::vector<RealTimeRun> real_time;  // the dynamic runs; empty: not run
  double real_time_factor = 0.0;       // the smallest of theirs; 0: not run
};

// The static scene the study runs for this filling and probe (the rigid probe still out of
// reach: run_filling places it against the prostate's equilibrium under gravity).
SceneSettings study_scene(const Options& options, double filling, Probe probe);
// Equilibrium under gravity, then under the probe in load steps. With an output directory,
// writes there the scene (<name>.yaml) and every equilibrium (<name>.pvd and its .vtu files,
// "probe_displacement" from the first), name = run_name.
// The same in explicit dynamics (`phymul prostate --scenes`, the real-time runs): the rigid
// probe placed against the prostate's equilibrium under gravity (one static relaxation).
SceneSettings dynamic_scene(const Options& options, double filling, Probe probe);
FillingResult run_filling(const Options& options, double filling, Probe probe,
                          const std::filesystem::path& out = {});
std::string run_name(double filling, Probe probe);  // "50mL_pressure"
// progress (optional) hears of each run before it starts: its index, the count and its name.
Study run_study(const Options& options, const std::filesystem::path& out = {},
                const std::function<void(int, int, const std::string&)>& progress = {});

std::string table(const Study& study);
std::string json(const Study& study);

}  // namespace phymul::prostate
