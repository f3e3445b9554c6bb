// The reference FEM on the same cube, plates and levels (each level solved from rest).
#include <chrono>
#include <cmath>

#include "phymul/fem.hpp"
#include "studies/truthcube_models.hpp"

namespace phymul::truthcube {

void run_fem(const Study& study, const std::vector<Bead>& beads, const StudyOptions& options,
             const Embedding& embedding, std::vector<LevelResult>& out) {
  const Plates plates = plate_nodes(study.mesh, study.frame);
  for (int l = 0; l < kLevels; ++l) {
    fem::Problem problem;
    problem.mesh = study.mesh;
    problem.material = {fem::Law::neo_hookean, options.young, options.poisson,
                        options.incompatible_modes ? fem::HexaElement::incompatible_modes
                                                   : fem::HexaElement::mean_dilatation};
    problem.load_steps = 4 * (l + 1);
    auto hold = [&](int node, int axis, double value) {
      problem.prescribed.push_back({node, axis, value});
    };
    for (int n : plates.base)
      for (int a = options.sliding ? 2 : 0; a < 3; ++a) hold(n, a, 0.0);
    for (int n : plates.plate)
      for (int a = options.sliding ? 2 : 0; a < 3; ++a)
        hold(n, a, a == 2 ? kStrain[l] * kEdge : 0.0);
    if (options.sliding) {
      hold(plates.centre, 0, 0.0);
      hold(plates.centre, 1, 0.0);
      hold(plates.on_x_line, 1, 0.0);
    }
    const auto start = std::chrono::steady_clock::now();
    const fem::Result solved = fem::solve_static(problem);
    if (!solved.converged)
      throw std::runtime_error("the reference FEM did not converge at level " +
                               std::to_string(l + 1) + ": " + solved.message);
    LevelResult r;
    r.level = l;
    r.model = "fem";
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    r.iterations = solved.newton_iterations;
    r.positions = study.mesh.points;
    for (size_t i = 0; i < r.positions.size(); ++i) r.positions[i] += solved.displacement[i];
    for (int n : plates.plate) r.plate_force += solved.reaction[n].z();
    r.plate_force = std::abs(r.plate_force);
    r.beads = embedding.apply(r.positions);
    r.metrics = compare(beads, l, r.beads);
    out.push_back(std::move(r));
  }
}

}  // namespace phymul::truthcube
