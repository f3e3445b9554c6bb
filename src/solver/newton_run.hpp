// The scene route to the reference finite elements: `simulation: {mode: static, solver:
// newton}` solves a scene's fem objects by fem::solve_static (implicit, Newton) instead of
// relaxing their explicit (TLED) forces.
#pragma once

#include <vector>

#include "phymul/fem.hpp"
#include "phymul/model.hpp"
#include "phymul/run.hpp"
#include "phymul/scene.hpp"

namespace phymul {

// What `solver: newton` cannot take (objects that are not fem-elastic, volume constraints,
// pressures, obstacles, contacts, doubled nodes) and `law: linear` outside it: one
// diagnostic each, at the offending field, saying what is allowed.
void check_newton_scene(const Scene& scene, std::vector<Diagnostic>& problems);

// The compiled model as one reference-FEM problem at its settings' end time: its fem cells
// (hexahedra, tetrahedra; wedges already cut) with each object's law, E and nu; the fixed
// and prescribed components at duration (scaled by fem's load steps); dead nodal loads: the
// `force` loads at duration plus gravity on the lumped node masses (what the relaxation
// applies). Stitched objects share their merged nodes.
fem::Problem newton_problem(const Model& model);

// run_scene for `solver: newton`: a frame and a monitors row at rest and after each
// converged load step; report.json with the Newton iterations, the support reactions and
// the applied load. Checkpoints at the end of load steps (interrupted, or every so many
// Newton iterations); a resumed run goes on from the last one as if never stopped. run_scene
// has checked the output directory.
RunReport run_newton(const Scene& scene, const RunOptions& options);

}  // namespace phymul
