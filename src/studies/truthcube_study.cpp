// The Truth Cube study: the cube of the data frame compressed to the three measured levels
// by the shape-memory model and by the reference FEM, each compared with the beads.
#include <chrono>
#include <stdexcept>

#include "phymul/calibration.hpp"
#include "phymul/simulation.hpp"
#include "phymul/studies/truthcube.hpp"
#include "studies/truthcube_models.hpp"

namespace phymul::truthcube {
namespace {

// Shape memory with its volume constraint, relaxed through the levels in turn (each level
// starts from the last equilibrium, in two load steps).
void run_shape_memory(const Study& study, const std::vector<Bead>& beads,
                      const StudyOptions& options, const Embedding& embedding,
                      std::vector<LevelResult>& out) {
  const Plates plates = plate_nodes(study.mesh, study.frame);
  Model model;
  MaterialSpec material;
  material.density = 1000.0;                                 // kg/m^3, silicone gel
  const double k = options.young * (kEdge / options.cells);  // positions do not depend on it
  material.stiffness = k;
  material.frame = options.frame;
  material.reaction = options.reaction;
  const int c = add_elastic_component(model, "cube", study.mesh, material);
  if (options.volume_constraint) add_volume_constraint(model, c);
  Schedule push;
  push.times = {0.0};
  push.values = {Vec3::Zero()};
  for (int l = 0; l < kLevels; ++l) {
    push.times.push_back(l + 1.0);
    push.values.push_back(Vec3(0, 0, kStrain[l] * kEdge));  // the plate moves towards +z
  }
  const std::array<bool, 3> all{true, true, true}, z_only{false, false, true};
  add_prescribed_displacement(
      model, {plates.base, options.sliding ? z_only : all, Schedule::constant(Vec3::Zero())});
  add_prescribed_displacement(model, {plates.plate, options.sliding ? z_only : all, push});
  if (options.sliding) {
    add_prescribed_displacement(
        model, {{plates.centre}, {true, true, true}, Schedule::constant(Vec3::Zero())});
    add_prescribed_displacement(
        model, {{plates.on_x_line}, {false, true, true}, Schedule::constant(Vec3::Zero())});
  }
  // The plate force at the K a scene giving E would get (calibrate_object); positions and
  // forces per unit K do not depend on the K relaxed with.
  MaterialSpec tissue = material;
  tissue.young = options.young;
  tissue.poisson = options.poisson;
  const double force_scale =
      calibration::calibrate_object("cube", study.mesh, tissue, options.volume_constraint)
          .stiffness /
      k;
  model.settings.tolerance = options.tolerance * k * (kEdge / options.cells);
  model.settings.max_iterations = 400000;
  model.settings.mode = SolveMode::static_equilibrium;  // relaxation masses (Simulator)
  model.settings.relaxation = Relaxation::fire;
  model.settings.solver = options.solver;
  finalize(model);
  Simulator sim(model);
  for (int l = 0; l < kLevels; ++l) {
    const auto start = std::chrono::steady_clock::now();
    LevelResult r;
    r.level = l;
    r.model = "lsm";
    for (double sub : {0.5, 1.0}) {
      // The half step only guides the path: loosely relaxed, it serves as well.
      const double tolerance = (sub < 1.0 ? 1000.0 : 1.0) * model.settings.tolerance;
      const StaticResult s = sim.relax(l + sub, model.settings.max_iterations, {}, tolerance);
      r.iterations += s.iterations;
      if (!s.converged)
        throw std::runtime_error("the shape-memory model did not reach equilibrium at level " +
                                 std::to_string(l + 1));
    }
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::vector<Vec3> reaction = sim.support_reactions();
    for (int n : plates.plate) r.plate_force += reaction[size_t(n)].z();
    r.plate_force = std::abs(r.plate_force) * force_scale;
    r.positions = sim.data().x;
    r.beads = embedding.apply(r.positions);
    r.metrics = compare(beads, l, r.beads);
    out.push_back(std::move(r));
  }
}

}  // namespace

Study run_study(const std::vector<Bead>& beads, const StudyOptions& options) {
  if (options.cells < 2 || options.cells > 64)
    throw std::invalid_argument("--cells must be in [2, 64] (got " + std::to_string(options.cells) +
                                ")");
  Study study;
  study.frame = locate_cube(beads);
  study.mesh = make_box(Vec3::Constant(kEdge), {options.cells, options.cells, options.cells},
                        CellType::hexa, study.frame.center);
  std::vector<Vec3> rest;
  for (const Bead& b : beads) rest.push_back(b.rest);
  const Embedding embedding = embed(study.mesh, rest);
  run_shape_memory(study, beads, options, embedding, study.results);
  if (options.fem) run_fem(study, beads, options, embedding, study.results);
  return study;
}

}  // namespace phymul::truthcube
