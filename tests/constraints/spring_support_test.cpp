// constraints: {type: spring}: nodes on linear springs to their rest positions, a compliant
// support where `fixed` is a rigid one.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"

namespace phymul {
namespace {

constexpr double kSpring = 40.0;  // N/m per node

Model block(const std::string& mode, const std::string& springs) {
  return compile_scene(
      parse_scene("simulation: {" + mode +
                      ", gravity: [0, 0, -9.81 m/s^2]}\n"
                      "objects:\n"
                      "  - name: block\n"
                      "    mesh: {generator: box, size: [40 mm, 30 mm, 20 mm], cells: [4, 3, 2]}\n"
                      "    material: {stiffness: 30 N/m, density: 1000 kg/m^3}\n"
                      "constraints:\n" +
                      springs,
                  "block.yaml"));
}

double total_mass(const Model& model) {
  double m = 0.0;
  for (double mi : model.mass) m += mi;
  return m;
}

// Every node on a spring: the springs carry the whole weight, so the nodes sink on average
// by M g / (n k), however the shape memory shares it among them.
TEST(SpringSupport, AnObjectOnSpringsSinksByItsWeightOverTheirStiffness) {
  Simulator sim(
      block("mode: static, tolerance: 1e-10 N",
            fmt::format("  - {{type: spring, object: block, stiffness: {} N/m}}\n", kSpring)));
  const Model& model = sim.model();
  ASSERT_TRUE(sim.relax(1.0, 200000).converged);
  const double weight = total_mass(model) * 9.81;
  double sink = 0.0;
  Vec3 held = Vec3::Zero();
  const std::vector<Vec3> reactions = sim.support_reactions();
  for (int i = 0; i < model.node_count(); ++i) {
    sink += sim.data().x[size_t(i)].z() - model.rest_position[size_t(i)].z();
    held += reactions[size_t(i)];
  }
  sink /= model.node_count();
  EXPECT_NEAR(sink, -weight / (model.node_count() * kSpring), 1e-9 * weight / kSpring);
  EXPECT_NEAR(held.z(), weight, 1e-8 * weight);  // the springs' reactions hold the weight
  EXPECT_NEAR(held.x(), 0.0, 1e-9 * weight);
  EXPECT_NEAR(held.y(), 0.0, 1e-9 * weight);
}

// A block hanging from springs on its top face sinks further than from fixed nodes, and
// the springs' stiffness enters the stable step (Gershgorin rows) as stiffness does.
TEST(SpringSupport, StifferSpringsApproachTheFixedSupport) {
  auto bottom_drop = [](const std::string& support) {
    Simulator sim(block("mode: static, tolerance: 1e-9 N", support));
    EXPECT_TRUE(sim.relax(1.0, 400000).converged);
    double z = 0.0, rest = 0.0;
    const Model& model = sim.model();
    for (int i : model.components[0].node_sets.at("bottom")) {
      z += sim.data().x[size_t(i)].z();
      rest += model.rest_position[size_t(i)].z();
    }
    return rest - z;
  };
  const double fixed = bottom_drop("  - {type: fixed, object: block, nodes: top}\n");
  std::vector<double> extra;  // the drop beyond the fixed support's
  for (double k : {10.0, 100.0, 1000.0, 10000.0}) {
    extra.push_back(
        bottom_drop(fmt::format("  - {{type: spring, object: block, nodes: top, stiffness: "
                                "{} N/m}}\n",
                                k)) -
        fixed);
    fmt::print("k {} N/m: {:.6g} m beyond the fixed support's drop\n", k, extra.back());
    EXPECT_GT(extra.back(), 0.0);
  }
  // Stiff springs stretch by the force they carry over k: the excess falls as 1/k.
  EXPECT_NEAR(extra[2] / extra[3], 10.0, 0.5);
  const Model soft = block("dt: auto", "  - {type: spring, object: block, stiffness: 1 N/m}\n");
  const Model hard = block("dt: auto", "  - {type: spring, object: block, stiffness: 1e4 N/m}\n");
  EXPECT_GT(stable_time_step(soft), stable_time_step(hard));
}

// The implicit steps' matrix carries the springs exactly: their static solution is the
// relaxation's.
TEST(SpringSupport, TheImplicitStaticSolutionIsTheRelaxations) {
  const std::string springs = "  - {type: spring, object: block, nodes: top, stiffness: 200 N/m}\n";
  Simulator relaxed(block("mode: static, tolerance: 1e-10 N", springs));
  ASSERT_TRUE(relaxed.relax(1.0, 400000).converged);
  Simulator implicit(block("mode: static, solver: implicit, tolerance: 1e-10 N", springs));
  ASSERT_TRUE(implicit.solve_static().converged);
  double largest = 0.0, apart = 0.0;
  const Model& model = relaxed.model();
  for (int i = 0; i < model.node_count(); ++i) {
    largest =
        std::max(largest, (relaxed.data().x[size_t(i)] - model.rest_position[size_t(i)]).norm());
    apart = std::max(apart, (relaxed.data().x[size_t(i)] - implicit.data().x[size_t(i)]).norm());
  }
  EXPECT_GT(largest, 1e-3);
  EXPECT_LT(apart, 1e-6 * largest);
}

}  // namespace
}  // namespace phymul
