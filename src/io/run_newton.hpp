// The scene route to the reference finite elements: `simulation: {mode: static, solver:
// newton}` solves a scene's fem objects by fem::solve_static (implicit, Newton) instead of
// relaxing their explicit (TLED) forces.
#pragma once

#include "phymul/run.hpp"
#include "phymul/scene.hpp"

namespace phymul {

// run_scene for `solver: newton`: a frame and a monitors row at rest and after each
// converged load step; report.json with the Newton iterations, the support reactions and
// the applied load. Checkpoints at the end of load steps (interrupted, or every so many
// Newton iterations); a resumed run goes on from the last one as if never stopped. run_scene
// has checked the output directory.
RunReport run_newton(const Scene& scene, const RunOptions& options);

}  // namespace phymul
