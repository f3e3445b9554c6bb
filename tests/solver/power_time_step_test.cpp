// simulation.dt_estimate: power. The highest frequency by power iteration on the linearised
// forces, against a spring chain's analytic spectrum and a dense eigensolver, and the time
// step it gives against the Gershgorin bound.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "phymul/forces.hpp"
#include "phymul/simulation.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

constexpr int kFree = 10;       // nodes of each chain between its two held ends
constexpr double kK = 100.0;    // N/m per fibre segment
constexpr double kEdge = 0.01;  // m

// Four parallel spring chains: a bar of kFree + 1 cubes whose four node lines along x are
// fibres, activated to half their rest length (so every segment pulls with K edge / 2 and
// the chain is at equilibrium), held at both ends. The shape memory is 1e-12 of the fibres'
// stiffness: it only gives the bar its masses.
Model chains() {
  Model model;
  const int c = add_elastic_component(
      model, "bar",
      make_box(Vec3(kEdge * (kFree + 1), kEdge, kEdge), {kFree + 1, 1, 1}, CellType::hexa),
      testing::material(kK * 1e-12));
  add_fibres(model, c, Vec3(1.0, 0.0, 0.0), kK, 0.5, Schedule::constant(Vec3(1.0, 0.0, 0.0)));
  double lo = 1e9, hi = -1e9;
  for (const Vec3& p : model.rest_position) lo = std::min(lo, p.x()), hi = std::max(hi, p.x());
  std::vector<int> ends;
  for (int i = 0; i < model.node_count(); ++i) {
    const double x = model.rest_position[size_t(i)].x();
    if (x < lo + 1e-9 || x > hi - 1e-9) ends.push_back(i);
  }
  add_fixed_nodes(model, ends);
  finalize(model);
  return model;
}

// A chain of n equal masses m between held ends, springs K: omega_j^2 = (4K/m)
// sin^2(j pi / (2 (n + 1))), the highest at j = n. Across the chain the pull K edge / 2 over
// the edge gives only K / 2, so the axial mode is the highest.
TEST(PowerTimeStep, BracketsASpringChainsHighestFrequency) {
  const Model model = chains();
  const double m = model.mass[size_t(model.components[0].nodes[1])];
  for (int i : model.components[0].nodes) {  // every free node: 2 cells of 8 corners
    if (model.inverse_mass[size_t(i)] != Vec3::Zero()) {
      ASSERT_DOUBLE_EQ(model.mass[size_t(i)], m);
    }
  }
  const double exact =
      std::sqrt(4.0 * kK / m) * std::sin(kFree * std::numbers::pi / (2.0 * (kFree + 1)));
  const Data rest = allocate_data(model);
  const FrequencyEstimate e = highest_frequency(model, rest, model.mass);
  // The Rayleigh quotient from below, its residual's interval above, both tight.
  EXPECT_LE(std::sqrt(e.rayleigh), exact * (1.0 + 1e-7));
  EXPECT_GE(e.omega(), exact * (1.0 - 1e-7));
  EXPECT_NEAR(e.omega(), exact, 1e-4 * exact);
  EXPECT_LT(e.iterations, 400);  // settled before the limit
  // The Gershgorin bound counts 4K on a chain's node: 2 sqrt(K/m), sin(10 pi / 22) = 0.990
  // of it, so the power estimate allows a 1 % longer step here.
  Model damped = model;
  const double gershgorin = stable_time_step(damped);
  EXPECT_NEAR(gershgorin, 2.0 / std::sqrt(4.0 * kK / m), 1e-9 * gershgorin);
  EXPECT_NEAR(verlet_stable_step(e.omega(), 0.0) / gershgorin,
              1.0 / std::sin(kFree * std::numbers::pi / (2.0 * (kFree + 1))), 1e-4);
}

// A shape-memory surface (icosphere, its top node held) against the eigenvalues of its force
// Jacobian, formed column by column and solved densely.
TEST(PowerTimeStep, MatchesADenseEigensolveOnAShapeMemorySurface) {
  Model model;
  add_elastic_component(model, "shell", make_ellipsoid_surface(Vec3(0.02, 0.02, 0.02), 2),
                        testing::surface_material(500.0, 0.01, FrameMode::polar));
  add_fixed_nodes(model, model.components[0].node_sets.at("top"));
  finalize(model);
  Data rest = allocate_data(model);
  compute_forces(model, rest, 0.0);
  std::vector<int> dof;
  for (int i = 0; i < model.node_count(); ++i)
    for (int a = 0; a < 3; ++a)
      if (model.inverse_mass[size_t(i)][a] != 0.0) dof.push_back(3 * i + a);
  const int n = int(dof.size());
  Eigen::MatrixXd a(n, n);
  const double h = 1e-8;  // m
  for (int col = 0; col < n; ++col) {
    Data plus = rest, minus = rest;
    plus.x[size_t(dof[col] / 3)][dof[col] % 3] += h;
    minus.x[size_t(dof[col] / 3)][dof[col] % 3] -= h;
    compute_forces(model, plus, 0.0);
    compute_forces(model, minus, 0.0);
    for (int row = 0; row < n; ++row) {
      const int i = dof[row] / 3, j = dof[col] / 3;
      a(row, col) = -(plus.f[size_t(i)][dof[row] % 3] - minus.f[size_t(i)][dof[row] % 3]) /
                    (2.0 * h * std::sqrt(model.mass[size_t(i)] * model.mass[size_t(j)]));
    }
  }
  // The shape memory with its exact reaction is an energy's gradient: a symmetric Jacobian.
  EXPECT_LT((a - a.transpose()).norm(), 1e-6 * a.norm());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> dense(0.5 * (a + a.transpose()),
                                                             Eigen::EigenvaluesOnly);
  const double exact = std::sqrt(dense.eigenvalues().maxCoeff());
  const FrequencyEstimate e = highest_frequency(model, rest, model.mass);
  EXPECT_NEAR(e.omega(), exact, 1e-3 * exact);
  EXPECT_LE(std::sqrt(e.rayleigh), exact * (1.0 + 1e-6));
  // Gershgorin's bound is the safe side but well off: the step it allows is shorter.
  EXPECT_LT(stable_time_step(model), 0.9 * verlet_stable_step(e.omega(), model.damping));
}

// The scene key: dt: auto takes dt_safety of 2/omega, with the damping's correction. Just
// below that limit the chains' highest mode stays as small as it started; 3 % above it, it
// grows 1.6-fold a step and the runaway guard stops the run with its message.
TEST(PowerTimeStep, TheSceneStepIsItsShareOfTheSharpLimit) {
  Model model = chains();
  model.damping = 5.0;
  model.settings.dt_estimate = DtEstimate::power;
  model.settings.dt_safety = 0.9;
  const Simulator sim(model);
  const FrequencyEstimate e = highest_frequency(sim.model(), sim.data(), sim.inertia());
  const double xi = 5.0 / (2.0 * e.omega());
  const double limit = 2.0 / e.omega() * (std::sqrt(1.0 + xi * xi) - xi);
  EXPECT_NEAR(sim.stable_dt(), limit, 1e-9 * limit);
  EXPECT_NEAR(sim.dt(), 0.9 * limit, 1e-9 * limit);
  // Every other node of the chains kicked one way, the others the other: the highest mode,
  // 8e-8 m of amplitude.
  auto kicked = [&](double share) {
    Simulator run(model);
    run.set_dt(share * run.stable_dt());
    for (int i = 0; i < run.model().node_count(); ++i) {
      const long j = std::lround(run.model().rest_position[size_t(i)].x() / kEdge + 100.0);
      run.data().v[size_t(i)] = Vec3(j % 2 == 0 ? 1e-4 : -1e-4, 0.0, 0.0);
    }
    return run;
  };
  Simulator below = kicked(0.99);
  for (int k = 0; k < 300; ++k) below.step();
  double largest = 0.0;
  for (int i = 0; i < below.model().node_count(); ++i)
    largest = std::max(largest,
                       (below.data().x[size_t(i)] - below.model().rest_position[size_t(i)]).norm());
  EXPECT_LT(largest, 2e-7);  // m
  Simulator above = kicked(1.03);
  try {
    for (int k = 0; k < 300; ++k) above.step();
    FAIL() << "300 steps at 1.03 times the power estimate's limit ran through";
  } catch (const InstabilityError& error) {
    EXPECT_NE(std::string(error.what()).find("a runaway, caught before any number overflowed"),
              std::string::npos)
        << error.what();
    EXPECT_LT(above.data().step, 100);
  }
}

}  // namespace
}  // namespace phymul
