// simulation.mass_scaling_dt: explicit FEM's mass scaling, inertia added to the nodes that
// alone set the stable step; gravity keeps the true masses.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"

namespace phymul {
namespace {

// A block hanging from its top face: its lumped corner nodes are 8 times lighter than its
// interior ones and set the Gershgorin limit alone.
Simulator hanging_block(const std::string& mass_scaling) {
  return Simulator(compile_scene(parse_scene(
      "simulation: {dt: auto, dt_safety: 0.5, damping: 40 1/s, gravity: [0, 0, -9.81 m/s^2]" +
          mass_scaling +
          "}\n"
          "objects:\n"
          "  - name: block\n"
          "    mesh: {generator: box, size: [40 mm, 30 mm, 20 mm], cells: [4, 3, 2]}\n"
          "    material: {stiffness: 30 N/m, density: 1000 kg/m^3}\n"
          "constraints:\n"
          "  - {type: fixed, object: block, nodes: top}\n",
      "block.yaml")));
}

TEST(MassScaling, LiftsTheLightNodesToTheTargetStep) {
  const Simulator plain = hanging_block("");
  const double limit = stable_time_step(plain.model());
  EXPECT_EQ(plain.added_inertia(), 0.0);
  const double target = 1.5 * limit;
  const Simulator scaled = hanging_block(fmt::format(", mass_scaling_dt: {:.17g} s", target));
  const Model& model = scaled.model();
  const std::vector<double> row = stiffness_row_sums(model);
  int lifted = 0;
  for (int i = 0; i < model.node_count(); ++i) {
    const double own_limit = 2.0 / std::sqrt(row[size_t(i)] / model.mass[size_t(i)]);
    if (own_limit < target) {
      ++lifted;  // exactly the inertia whose Gershgorin limit is the target
      EXPECT_NEAR(2.0 / std::sqrt(row[size_t(i)] / scaled.inertia()[size_t(i)]), target,
                  1e-12 * target);
    } else {
      EXPECT_EQ(scaled.inertia()[size_t(i)], model.mass[size_t(i)]);
    }
    EXPECT_EQ(model.mass[size_t(i)], plain.model().mass[size_t(i)]);  // gravity's masses
  }
  EXPECT_GT(lifted, 0);
  EXPECT_LT(lifted, model.node_count());
  double omega2 = 0.0;  // the undamped limit is the target; damping lowers the step a little
  for (int i = 0; i < model.node_count(); ++i)
    omega2 = std::max(omega2, row[size_t(i)] / scaled.inertia()[size_t(i)]);
  EXPECT_NEAR(2.0 / std::sqrt(omega2), target, 1e-12 * target);
  EXPECT_NEAR(scaled.dt(), 0.5 * stable_time_step(model, scaled.inertia()), 1e-15);
  // What run reports and `phymul check` prints: the estimate the step was taken from.
  EXPECT_EQ(scaled.stable_dt(), stable_time_step(model, scaled.inertia()));
  EXPECT_EQ(plain.stable_dt(), limit);
  EXPECT_GT(scaled.dt(), 1.4 * plain.dt());
  double added = 0.0;
  for (int i = 0; i < model.node_count(); ++i)
    added += scaled.inertia()[size_t(i)] - model.mass[size_t(i)];
  EXPECT_NEAR(scaled.added_inertia(), added, 1e-15);
}

TEST(MassScaling, KeepsTheEquilibrium) {
  // Same hanging shape with and without: the forces, gravity included, do not change.
  Simulator plain = hanging_block("");
  Simulator scaled = hanging_block(
      fmt::format(", mass_scaling_dt: {:.17g} s", 1.5 * stable_time_step(plain.model())));
  while (plain.data().time < 3.0) plain.step();
  while (scaled.data().time < 3.0) scaled.step();
  double sag = 0.0, apart = 0.0;
  for (size_t i = 0; i < plain.data().x.size(); ++i) {
    sag = std::max(sag, (plain.data().x[i] - plain.model().rest_position[i]).norm());
    apart = std::max(apart, (plain.data().x[i] - scaled.data().x[i]).norm());
  }
  EXPECT_GT(sag, 1e-3);  // it hangs visibly
  EXPECT_LT(apart, 1e-6 * sag);
}

TEST(MassScaling, IsOnlyForDynamics) {
  // Static relaxation has its own fictitious masses; the key leaves them alone.
  const Model model = compile_scene(
      parse_scene("simulation: {mode: static, mass_scaling_dt: 1 s}\n"
                  "objects:\n"
                  "  - name: block\n"
                  "    mesh: {generator: box, size: [40 mm, 30 mm, 20 mm], cells: [4, 3, 2]}\n"
                  "    material: {stiffness: 30 N/m, density: 1000 kg/m^3}\n",
                  "static.yaml"));
  const Simulator sim(model);
  EXPECT_NEAR(sim.dt(), 0.5 * stable_time_step(model), 1e-15);
}

TEST(MassScaling, RefusesANonPositiveTarget) {
  try {
    parse_scene("simulation: {mass_scaling_dt: -1 ms}\nobjects: []\n", "bad.yaml");
    FAIL() << "accepted a negative mass_scaling_dt";
  } catch (const SceneError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("mass_scaling_dt"), std::string::npos) << m;
    EXPECT_NE(m.find("bad.yaml:1"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace phymul
