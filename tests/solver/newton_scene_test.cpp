// The scene route to the reference finite elements (`simulation: {mode: static, solver:
// newton}`), against analytic solutions and the explicit elements relaxed on the same scene.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <string>

#include "io/run_newton.hpp"
#include "phymul/fem.hpp"
#include "phymul/model.hpp"
#include "phymul/run.hpp"
#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "support/process.hpp"
#include "support/results.hpp"

namespace phymul {
namespace {

struct Solved {
  Model model;
  fem::Problem problem;
  fem::Result result;
};

Solved solve_newton(const std::string& text) {
  const Scene scene = parse_scene(text, "newton.yaml");
  Solved s{compile_scene(scene), {}, {}};
  s.problem = newton_problem(s.model);
  s.result = fem::solve_static(s.problem);
  return s;
}

// Node positions keyed by rest position (rounded to 1 nm), to compare different meshings.
std::map<std::array<long, 3>, Vec3> by_rest_position(const Model& model,
                                                     const std::vector<Vec3>& u) {
  std::map<std::array<long, 3>, Vec3> out;
  for (int i = 0; i < model.node_count(); ++i) {
    const Vec3& X = model.rest_position[size_t(i)];
    out[{std::lround(X.x() * 1e9), std::lround(X.y() * 1e9), std::lround(X.z() * 1e9)}] =
        u[size_t(i)];
  }
  return out;
}

// A bar of one cell across (uniform traction from four equal corner forces), clamped at x = 0,
// nu = 0: the uniform uniaxial stress is in the element space, so u(x) = F x / (E A) exactly.
constexpr double kBarForce = 1.0;  // N, total
constexpr double kBarArea = 1e-4;  // m^2

std::string bar_scene(const std::string& objects, const std::string& loaded) {
  return fmt::format(R"(
simulation: {{mode: static, solver: newton, load_steps: 2, tolerance: 1e-12 N}}
objects:
{}
loads:
  - {{type: force, object: {}, nodes: right, force: [0.25 N, 0, 0]}}
constraints:
  - {{type: fixed, object: a, nodes: left}}
)",
                     objects, loaded);
}

TEST(NewtonScene, LinearBarUnderEndForceStretchesByFLOverEA) {
  const double young = 1e5;
  const Solved s = solve_newton(bar_scene(R"(
  - name: a
    mesh: {generator: box, size: [0.1, 0.01, 0.01], cells: [10, 1, 1], center: [0.05, 0, 0]}
    material: {model: fem, law: linear, young: 100 kPa, poisson: 0, density: 1000})",
                                          "a"));
  ASSERT_TRUE(s.result.converged) << s.result.message;
  EXPECT_EQ(s.result.load_steps_done, 2);
  for (int i = 0; i < s.model.node_count(); ++i) {
    const double x = s.model.rest_position[size_t(i)].x();
    const double expected = kBarForce * x / (young * kBarArea);  // 0.01 m at the end
    const Vec3& u = s.result.displacement[size_t(i)];
    EXPECT_NEAR(u.x(), expected, 1e-9 * 0.01) << "node " << i << " at x = " << x;
    EXPECT_NEAR(u.y(), 0.0, 1e-12) << i;
    EXPECT_NEAR(u.z(), 0.0, 1e-12) << i;
  }
}

// Two materials stitched in series: each object keeps its own modulus, and the end moves by
// F (L1 / E1 + L2 / E2) / A.
TEST(NewtonScene, StitchedBarsOfTwoMaterialsStretchInSeries) {
  const Solved s = solve_newton(bar_scene(R"(
  - name: a
    mesh: {generator: box, size: [0.05, 0.01, 0.01], cells: [5, 1, 1], center: [0.025, 0, 0]}
    material: {model: fem, law: linear, young: 100 kPa, poisson: 0, density: 1000}
  - name: b
    mesh: {generator: box, size: [0.05, 0.01, 0.01], cells: [5, 1, 1], center: [0.075, 0, 0]}
    material: {model: fem, law: linear, young: 300 kPa, poisson: 0, density: 1000}
stitches:
  - {object: a, with: b, nodes: right, with_nodes: left})",
                                          "b"));
  ASSERT_TRUE(s.result.converged) << s.result.message;
  EXPECT_EQ(s.model.node_count(), 2 * 24 - 4);  // the shared face merged
  for (int i = 0; i < s.model.node_count(); ++i) {
    const double x = s.model.rest_position[size_t(i)].x();
    const double expected = x <= 0.05 ? kBarForce * x / (1e5 * kBarArea)
                                      : kBarForce * (0.05 / 1e5 + (x - 0.05) / 3e5) / kBarArea;
    EXPECT_NEAR(s.result.displacement[size_t(i)].x(), expected, 1e-9 * 0.01) << "x = " << x;
  }
}

// A Neo-Hookean cantilever bending under gravity (tip deflection ~ 20 % of its length).
std::string cantilever(const std::string& solver, const std::string& element,
                       const std::string& extra = "") {
  return fmt::format(R"(
simulation: {{mode: static, solver: {}, load_steps: 4, tolerance: 1e-13 N,
              gravity: [0, 0, -9.81], max_iterations: 2000000}}
objects:
  - name: beam
    mesh: {{generator: box, element: {}, size: [0.04, 0.01, 0.01], cells: [8, 2, 2],
           center: [0.02, 0, 0]}}
    material: {{model: fem, young: 20 kPa, poisson: 0.3, density: 1000}}
constraints:
  - {{type: fixed, object: beam, nodes: left}}
{})",
                     solver, element, extra);
}

// On linear tetrahedra the explicit elements (TLED, one point) and the reference ones have the
// same Neo-Hookean energy, so the relaxed equilibrium is Newton's up to the relaxation's
// residual. The difference scales with its tolerance (measured: 7.9e-11 m at 1e-11 N,
// 6.0e-13 m at 1e-13 N, for a 10.6 mm tip deflection): it is the residual over the soft
// bending stiffness, not a difference of the discretisations.
TEST(NewtonScene, TetrahedralCantileverMatchesTheRelaxedExplicitElements) {
  const Solved newton = solve_newton(cantilever("newton", "tetra"));
  ASSERT_TRUE(newton.result.converged) << newton.result.message;
  Simulator relaxed(compile_scene(parse_scene(cantilever("relaxation", "tetra"), "r.yaml")));
  const StaticResult r = relaxed.solve_static();
  ASSERT_TRUE(r.converged) << r.residual;
  double tip = 0.0, largest_difference = 0.0;
  for (int i = 0; i < newton.model.node_count(); ++i) {
    const Vec3& u = newton.result.displacement[size_t(i)];
    tip = std::max(tip, -u.z());
    const Vec3 relaxed_u = relaxed.data().x[size_t(i)] - relaxed.model().rest_position[size_t(i)];
    largest_difference = std::max(largest_difference, (u - relaxed_u).norm());
  }
  EXPECT_GT(tip, 0.004);  // a large deflection: the nonlinearity is exercised
  EXPECT_LT(largest_difference, 1e-9 * tip) << "tip " << tip;
}

// Two objects stitched at x = 2 cm solve as the one object they make up.
TEST(NewtonScene, StitchedHalvesMatchTheWholeBeam) {
  const Solved whole = solve_newton(cantilever("newton", "hexa"));
  const Solved halves = solve_newton(R"(
simulation: {mode: static, solver: newton, load_steps: 4, tolerance: 1e-11 N,
             gravity: [0, 0, -9.81]}
objects:
  - name: root
    mesh: {generator: box, size: [0.02, 0.01, 0.01], cells: [4, 2, 2], center: [0.01, 0, 0]}
    material: {model: fem, young: 20 kPa, poisson: 0.3, density: 1000}
  - name: tip
    mesh: {generator: box, size: [0.02, 0.01, 0.01], cells: [4, 2, 2], center: [0.03, 0, 0]}
    material: {model: fem, young: 20 kPa, poisson: 0.3, density: 1000}
stitches:
  - {object: root, with: tip, nodes: right, with_nodes: left}
constraints:
  - {type: fixed, object: root, nodes: left}
)");
  ASSERT_TRUE(whole.result.converged) << whole.result.message;
  ASSERT_TRUE(halves.result.converged) << halves.result.message;
  const auto a = by_rest_position(whole.model, whole.result.displacement);
  const auto b = by_rest_position(halves.model, halves.result.displacement);
  ASSERT_EQ(a.size(), b.size());
  double tip = 0.0;
  for (const auto& [key, u] : a) {
    ASSERT_TRUE(b.count(key));
    tip = std::max(tip, u.norm());
    EXPECT_LT((u - b.at(key)).norm(), 1e-10 * 0.004) << key[0] << " " << key[2];
  }
  EXPECT_GT(tip, 0.004);
}

// The supports carry the weight (rho V g) and the tip loads: reactions and loads balance.
TEST(NewtonScene, SupportReactionsBalanceGravityAndForces) {
  const Solved s = solve_newton(cantilever(
      "newton", "hexa",
      "loads:\n  - {type: force, object: beam, nodes: right, force: [1 mN, -2 mN, -3 mN]}"));
  ASSERT_TRUE(s.result.converged) << s.result.message;
  Vec3 reaction = Vec3::Zero();
  for (const fem::Dirichlet& d : s.problem.prescribed)
    reaction[d.axis] += s.result.reaction[size_t(d.node)][d.axis];
  const double weight = 1000.0 * 0.04 * 0.01 * 0.01 * 9.81;  // N
  const int right_nodes = 3 * 3;
  const Vec3 load = Vec3(0, 0, -weight) + right_nodes * Vec3(1e-3, -2e-3, -3e-3);
  EXPECT_LT((reaction + load).norm(), 1e-9 * load.norm()) << reaction.transpose();
}

// run_scene writes a frame per load step and report.json with the Newton figures; the
// reactions it reports balance the loads it reports.
TEST(NewtonScene, RunWritesLoadStepFramesAndReport) {
  testing::TempDir dir;
  const auto scene_file = dir.path() / "beam.yaml";
  std::ofstream(scene_file) << cantilever("newton", "hexa");
  RunOptions options;
  options.output_dir = dir.path() / "out";
  const RunReport r = run_scene(load_scene(scene_file), options);
  EXPECT_EQ(r.status, "completed") << r.message;
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.frames, 5);  // rest and 4 load steps
  EXPECT_EQ(r.load_steps_done, 4);
  EXPECT_GT(r.steps, 4);
  EXPECT_LE(r.residual, 1e-11);
  EXPECT_NEAR(r.simulated_time, 1.0, 1e-15);
  const double weight = 1000.0 * 0.04 * 0.01 * 0.01 * 9.81;
  EXPECT_NEAR(r.applied_load.z(), -weight, 1e-12 * weight);
  EXPECT_LT((r.support_reaction + r.applied_load).norm(), 1e-9 * weight);
  const std::string json = testing::read_text(options.output_dir / "report.json");
  EXPECT_NE(json.find("\"solver\": \"newton\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"load_steps_done\": 4"), std::string::npos) << json;
  EXPECT_NE(json.find("\"support_reaction_N\": ["), std::string::npos) << json;
  EXPECT_TRUE(std::filesystem::exists(options.output_dir / "beam_000004.vtu"));
  EXPECT_FALSE(std::filesystem::exists(options.output_dir / "beam_000005.vtu"));
}

// Stopped after its first load step, a Newton run leaves a checkpoint; resumed, it ends with
// the files of the run never stopped, byte for byte. With incompatible-mode hexahedra the mode
// amplitudes, and with both the factorised tangent the next predictor solves with, are part
// of where the solve stands.
TEST(NewtonScene, StoppedAfterALoadStepAndResumedWritesTheSameFiles) {
  for (const std::string hexa : {"mean-dilatation", "incompatible-modes"}) {
    testing::TempDir dir;
    const auto scene_file = dir.path() / "beam.yaml";
    std::string text = cantilever("newton", "hexa");
    text.replace(text.find("density: 1000}"), 14, "density: 1000, hexa: " + hexa + "}");
    // Stiffer than the other tests' beam: at 20 kPa the incompatible modes' tangent turns
    // indefinite in the last load step and the solve stops there.
    text.replace(text.find("young: 20 kPa"), 13, "young: 200 kPa");
    std::ofstream(scene_file) << text;
    RunOptions options;
    options.output_dir = dir.path() / "full";
    ASSERT_EQ(run_scene(load_scene(scene_file), options).status, "completed");
    options.output_dir = dir.path() / "part";
    options.stop_after_steps = 1;  // at the end of the first load step
    const RunReport r = run_scene(load_scene(scene_file), options);
    EXPECT_EQ(r.status, "interrupted") << hexa;
    EXPECT_FALSE(r.converged);
    EXPECT_EQ(r.load_steps_done, 1);
    EXPECT_EQ(r.frames, 2);
    EXPECT_NE(r.message.find("phymul run --resume"), std::string::npos) << r.message;
    options.stop_after_steps = 0;
    options.resume = true;
    EXPECT_EQ(run_scene(load_scene(scene_file), options).status, "completed") << hexa;
    testing::expect_same_results(dir.path() / "full", dir.path() / "part");
  }
}

// The top pushed 1.5 heights down through a fixed bottom: no equilibrium without inverting
// cells. The CLI exits 4; the report says so and holds only the rest frame.
TEST(NewtonScene, ImpossibleLoadIsNotConvergedWithExitCodeFour) {
  testing::TempDir dir;
  const auto scene_file = dir.path() / "crush.yaml";
  std::ofstream(scene_file) << R"(
simulation: {mode: static, solver: newton, load_steps: 1}
objects:
  - name: cube
    mesh: {generator: box, size: [0.01, 0.01, 0.01], cells: [2, 2, 2]}
    material: {model: fem, young: 10 kPa, poisson: 0.3, density: 1000}
constraints:
  - {type: fixed, object: cube, nodes: bottom}
  - {type: displacement, object: cube, nodes: top, axes: z,
     schedule: [{t: 0, value: [0, 0, 0]}, {t: 1, value: [0, 0, -0.015]}]}
)";
  const auto check = testing::run_command(testing::cli() + " check " + scene_file.string());
  EXPECT_EQ(check.exit_code, 0) << check.output;
  EXPECT_NE(check.output.find("static, Newton"), std::string::npos) << check.output;
  const auto out = dir.path() / "out";
  const auto r =
      testing::run_command(testing::cli() + " run " + scene_file.string() + " -o " + out.string());
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("not-converged after 0 of 1 load steps"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("did not converge"), std::string::npos) << r.output;
  const std::string json = testing::read_text(out / "report.json");
  EXPECT_NE(json.find("\"status\": \"not-converged\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"load_steps_done\": 0"), std::string::npos) << json;
  EXPECT_TRUE(std::filesystem::exists(out / "crush_000000.vtu"));
  EXPECT_FALSE(std::filesystem::exists(out / "crush_000001.vtu"));
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// The Truth Cube's bonded compression written as a scene (80 mm cube, 8^3 hexahedra,
// E = 14.9 kPa, nu = 0.499, top pushed 4 mm with x and y held): the plate force is the
// reference solver's table value (src/fem/README.md, built there from fem::Problem directly).
TEST(NewtonScene, BondedCompressionSceneGivesTheReferencePlateForce) {
  const Solved s = solve_newton(R"(
simulation: {mode: static, solver: newton, load_steps: 10, duration: 2 s}
objects:
  - name: cube
    mesh: {generator: box, size: [80 mm, 80 mm, 80 mm], cells: [8, 8, 8]}
    material: {model: fem, young: 14.9 kPa, poisson: 0.499, density: 1000 kg/m^3}
constraints:
  - {type: fixed, object: cube, nodes: bottom}
  - type: displacement
    object: cube
    nodes: top
    schedule: [{t: 0 s, value: [0, 0, 0]}, {t: 1 s, value: [0, 0, -2 mm]},
               {t: 2 s, value: [0, 0, -4 mm]}]
)");
  ASSERT_TRUE(s.result.converged) << s.result.message;
  double top_force = 0.0;
  for (int i : s.model.components[0].node_sets.at("top")) top_force -= s.result.reaction[i].z();
  EXPECT_NEAR(top_force, 6.322369615, 1e-8);
}

// The same cube with `hexa: incompatible-modes`, CalculiX's C3D8I on these cells: CalculiX 2.20
// gives a plate force of 6.4307 N (tests/fem/calculix_test.cpp prints it; our element agrees
// with it to 2e-7), 1.7 % above the mean-dilatation element.
TEST(NewtonScene, IncompatibleModeHexahedraGiveCalculixPlateForce) {
  const Solved s = solve_newton(R"(
simulation: {mode: static, solver: newton, load_steps: 4}
objects:
  - name: cube
    mesh: {generator: box, size: [80 mm, 80 mm, 80 mm], cells: [8, 8, 8]}
    material: {model: fem, hexa: incompatible-modes, young: 14.9 kPa, poisson: 0.499,
               density: 1000 kg/m^3}
constraints:
  - {type: fixed, object: cube, nodes: bottom}
  - {type: displacement, object: cube, nodes: top, schedule: [{t: 1 s, value: [0, 0, -4 mm]}]}
)");
  ASSERT_TRUE(s.result.converged) << s.result.message;
  double top_force = 0.0;
  for (int i : s.model.components[0].node_sets.at("top")) top_force -= s.result.reaction[i].z();
  EXPECT_NEAR(top_force, 6.4307, 1e-4);  // CalculiX's value, as printed to 5 digits
}

TEST(NewtonScene, UnheldObjectIsNotConvergedWithAMessage) {
  const Solved s = solve_newton(R"(
simulation: {mode: static, solver: newton, load_steps: 1}
objects:
  - name: cube
    mesh: {generator: box, size: [0.01, 0.01, 0.01], cells: [2, 2, 2]}
    material: {model: fem, young: 10 kPa, poisson: 0.3, density: 1000}
loads:
  - {type: force, object: cube, nodes: top, force: [0, 0, 1 mN]}
)");
  EXPECT_FALSE(s.result.converged);
  EXPECT_FALSE(s.result.message.empty());
  EXPECT_EQ(s.result.load_steps_done, 0);
}

}  // namespace
}  // namespace phymul
