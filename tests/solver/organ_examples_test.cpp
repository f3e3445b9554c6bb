// The examples of Fig. 1 and the muscle, run as the user runs them, against hand
// calculations.
#include <gtest/gtest.h>

#include <filesystem>

#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "solver/rigid.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

std::filesystem::path examples() { return testing::source_dir() / "examples"; }

int component(const Model& model, const std::string& name) {
  for (int c = 0; c < int(model.components.size()); ++c)
    if (model.components[c].name == name) return c;
  ADD_FAILURE() << "no component " << name;
  return 0;
}

int body_of(const Model& model, const std::string& name) {
  const int c = component(model, name);
  for (int b = 0; b < int(model.rigid_bodies.size()); ++b)
    if (model.rigid_bodies[b].component == c) return b;
  ADD_FAILURE() << "no rigid body " << name;
  return 0;
}

TEST(OrganExamples, LigamentStaticEquilibriumMatchesTheHandCalculation) {
  Simulator sim(compile_scene(load_scene(examples() / "fig1c_ligament.yaml")));
  const StaticResult r = sim.solve_static();
  ASSERT_TRUE(r.converged) << r.residual;
  const Model& model = sim.model();
  // By hand: bones 2 x 2 x 1 cm of 1900 kg/m^3, ligament 1 x 1 x 2 cm of 1100 kg/m^3, and
  // 25 lower-face nodes loaded with 4 mN each.
  const double g = 9.81;
  const double bone = 1900.0 * 0.02 * 0.02 * 0.01, ligament = 1100.0 * 0.01 * 0.01 * 0.02;
  const double load = 25 * 0.004;
  double total_mass = 0.0;
  for (double m : model.mass) total_mass += m;
  EXPECT_NEAR(total_mass, 2 * bone + ligament, 1e-15);
  // The held upper bone carries everything: its reaction is the total weight plus the load.
  const std::vector<Vec3> reactions = sim.support_reactions();
  const RigidBody& upper = model.rigid_bodies[body_of(model, "upper_bone")];
  Vec3 reaction = Vec3::Zero();
  for (int i : upper.nodes) reaction += reactions[i];
  const double expected = (2 * bone + ligament) * g + load;  // 0.171 N + 0.1 N
  // Each free node may keep a residual up to the tolerance: that bounds the imbalance.
  int free_nodes = 0;
  for (int i = 0; i < model.node_count(); ++i) free_nodes += model.rigid_body_of[i] < 0;
  const double bound = (free_nodes + 1) * model.settings.tolerance;
  EXPECT_NEAR(reaction.z(), expected, bound);
  EXPECT_NEAR(reaction.head<2>().norm(), 0.0, 1e-9);
  // The ligament pulls the lower bone up with its weight plus the load: the body is in
  // balance, and by symmetry it hangs straight, centred under the ligament.
  const int lower = body_of(model, "lower_bone");
  Vec3 force, torque;
  rigid_load(model, sim.data(), lower, force, torque, false);
  EXPECT_LT(force.norm(), 1e-6);
  const RigidBodyState& b = sim.data().bodies[lower];
  EXPECT_LT(b.center.head<2>().norm(), 1e-9);
  EXPECT_LT(b.orientation.angularDistance(model.rigid_bodies[lower].rest_orientation), 1e-9);
  // It went down: the ligament stretched under (bone + load) = 0.175 N.
  const double drop = model.rigid_bodies[lower].rest_center.z() - b.center.z();
  EXPECT_GT(drop, 1e-4);
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

TEST(OrganExamples, MuscleLiftsTheLoad) {
  Simulator sim(compile_scene(load_scene(examples() / "muscle.yaml")));
  const Model& model = sim.model();
  const int lower = body_of(model, "lower_bone");
  auto height = [&] { return sim.data().bodies[lower].center.z(); };
  double before = 0.0, lowest = 1.0;
  while (sim.data().time < model.settings.duration) {
    sim.step();
    if (sim.data().time <= 0.5) before = height();  // sagged under the load, inactive
    lowest = std::min(lowest, height());
    // The muscle's end nodes move with the bones, at every step.
    for (const auto& [a, b] : model.doubled_pairs) ASSERT_EQ(sim.data().x[a], sim.data().x[b]);
  }
  const double rest = model.rigid_bodies[lower].rest_center.z();
  EXPECT_LT(before, rest);  // the load stretched the passive muscle
  // Full activation asks the 4 cm fibres to shorten by 30 %, 12 mm: the shape memory and
  // the load (0.2 N + the bone's 0.075 N) hold some of it back. Measured: 11.7 mm.
  const double lift = height() - before;
  EXPECT_GT(lift, 0.8 * 0.012);
  EXPECT_LT(lift, 0.012 + (rest - before));
  EXPECT_LT(sim.kinetic_energy(), 1e-8);  // settled
  // The muscle kept its volume while it shortened.
  EXPECT_NEAR(sim.component_volumes()[component(model, "muscle")], 4e-6, 1e-15);
}

}  // namespace
}  // namespace phymul
