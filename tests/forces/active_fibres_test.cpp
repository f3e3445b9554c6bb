// Active components: fibre lines, forces as the gradient of their energy, contraction.
#include "forces/active_fibres.hpp"

#include <gtest/gtest.h>

#include "phymul/simulation.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

Model strip(double ratio, Schedule activation) {
  Model model;
  add_elastic_component(model, "muscle",
                        make_box(Vec3(0.04, 0.01, 0.01), {4, 1, 1}, CellType::hexa),
                        testing::material(20.0));
  model.components[0].kind = ObjectType::active;
  add_fibres(model, 0, Vec3(2.0, 0.0, 0.0), 100.0, ratio, std::move(activation));
  return model;
}

TEST(ActiveFibres, OneFibrePerNodeLineAlongTheDirection) {
  const Model model = strip(0.3, Schedule::constant(Vec3::Zero()));
  const FibreBundle& b = model.fibres[0];
  ASSERT_EQ(b.polylines.rows(), 4);  // (1 + 1) x (1 + 1) lines of 5 nodes
  for (int p = 0; p < 4; ++p) {
    const auto line = b.polylines.row(p);
    ASSERT_EQ(line.size(), 5u);
    for (size_t k = 1; k < line.size(); ++k)
      EXPECT_NEAR(model.rest_position[line[k]].x() - model.rest_position[line[k - 1]].x(), 0.01,
                  1e-15);
  }
  for (double l : b.rest_length) EXPECT_NEAR(l, 0.01, 1e-15);
}

TEST(ActiveFibres, ActivationShortensTheRestLength) {
  const Model model = strip(0.3, Schedule{{0.0, 1.0}, {Vec3::Zero(), Vec3(1.0, 0, 0)}});
  const FibreBundle& b = model.fibres[0];
  std::vector<Vec3> f(size_t(model.node_count()), Vec3::Zero());
  // At rest and inactive: nothing. Half active at t = 0.5: each segment pulls with
  // K (l0 - l0 (1 - 0.5 * 0.3)) = 100 * 0.0015 N; interior nodes are balanced.
  EXPECT_EQ(add_fibre_forces(b, model.rest_position, 0.0, f), 0.0);
  for (const Vec3& fi : f) EXPECT_EQ(fi, Vec3::Zero());
  const double energy = add_fibre_forces(b, model.rest_position, 0.5, f);
  EXPECT_NEAR(energy, 16 * 0.5 * 100.0 * 0.0015 * 0.0015, 1e-15);
  Vec3 total = Vec3::Zero();
  for (int p = 0; p < b.polylines.rows(); ++p) {
    const auto line = b.polylines.row(p);
    EXPECT_NEAR(f[line.front()].x(), 0.15, 1e-14);  // pulled towards the other end
    EXPECT_NEAR(f[line.back()].x(), -0.15, 1e-14);
    for (size_t k = 1; k + 1 < line.size(); ++k) EXPECT_NEAR(f[line[k]].norm(), 0.0, 1e-14);
  }
  for (const Vec3& fi : f) total += fi;
  EXPECT_LT(total.norm(), 1e-15);
  // A fibre never pushes: squeezed below its active length it carries no force.
  std::vector<Vec3> squeezed = model.rest_position;
  for (Vec3& x : squeezed) x.x() *= 0.5;
  std::fill(f.begin(), f.end(), Vec3::Zero());
  EXPECT_EQ(add_fibre_forces(b, squeezed, 1.0, f), 0.0);
}

TEST(ActiveFibres, ForcesAreMinusTheEnergyGradient) {
  const Model model = strip(0.4, Schedule::constant(Vec3(0.7, 0, 0)));
  std::vector<Vec3> x = model.rest_position;
  std::mt19937 rng(2);
  std::normal_distribution<double> n(0.0, 1e-3);
  for (Vec3& p : x) p += testing::random_vec3(n, rng);
  std::vector<Vec3> f(x.size(), Vec3::Zero()), scratch(x.size());
  add_fibre_forces(model.fibres[0], x, 0.0, f);
  const double h = 1e-8;
  for (int i = 0; i < int(x.size()); i += 3)
    for (int a = 0; a < 3; ++a) {
      std::vector<Vec3> xp = x, xm = x;
      xp[i][a] += h;
      xm[i][a] -= h;
      const double dE = add_fibre_forces(model.fibres[0], xp, 0.0, scratch) -
                        add_fibre_forces(model.fibres[0], xm, 0.0, scratch);
      EXPECT_NEAR(f[i][a], -dE / (2 * h), 1e-7) << "node " << i << " axis " << a;
    }
}

TEST(ActiveFibres, AListedPolylineBendsThroughItsNodes) {
  Model model;
  add_elastic_component(model, "muscle",
                        make_box(Vec3(0.02, 0.02, 0.01), {2, 2, 1}, CellType::hexa),
                        testing::material(20.0));
  // An L through the bottom layer: (0,0) -> (2,0) -> (2,2), ids i + 3 j.
  add_fibre_polylines(model, 0, {{0, 1, 2, 5, 8}}, 10.0, 0.5, Schedule::constant(Vec3(1, 0, 0)));
  const FibreBundle& b = model.fibres[0];
  ASSERT_EQ(b.rest_length.size(), 4u);
  std::vector<Vec3> f(size_t(model.node_count()), Vec3::Zero());
  add_fibre_forces(b, model.rest_position, 0.0, f);
  // Each segment (1 cm, active length 5 mm) pulls with 10 N/m x 5 mm = 0.05 N: the corner
  // node 2 is pulled along both legs, towards the inside of the L.
  EXPECT_NEAR((f[2] - Vec3(-0.05, 0.05, 0.0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((f[0] - Vec3(0.05, 0.0, 0.0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((f[8] - Vec3(0.0, -0.05, 0.0)).norm(), 0.0, 1e-15);
  EXPECT_THROW(add_fibre_polylines(model, 0, {{0, 99}}, 10.0, 0.5, Schedule{}),
               std::invalid_argument);
  EXPECT_THROW(add_fibre_polylines(model, 0, {{3}}, 10.0, 0.5, Schedule{}), std::invalid_argument);
}

TEST(ActiveFibres, ActivationOutsideItsRangeIsRefused) {
  EXPECT_THROW(strip(0.3, Schedule::constant(Vec3(1.5, 0, 0))), std::invalid_argument);
  EXPECT_THROW(strip(1.0, Schedule::constant(Vec3::Zero())), std::invalid_argument);
  EXPECT_THROW(strip(0.0, Schedule::constant(Vec3::Zero())), std::invalid_argument);
}

TEST(ActiveFibres, AFreeMuscleContractsTowardsItsActiveLengthAtConstantVolume) {
  // A muscle keeps its volume: fibres shorten it and it thickens. Fibres as stiff as the
  // shape memory (20 N/m), asking for 20 % shortening at full activation.
  Model model;
  add_elastic_component(model, "muscle",
                        make_box(Vec3(0.04, 0.01, 0.01), {8, 2, 2}, CellType::hexa),
                        testing::material(20.0));
  add_volume_constraint(model, 0);
  add_fibres(model, 0, Vec3::UnitX(), 20.0, 0.2, Schedule::constant(Vec3(1.0, 0, 0)));
  model.damping = 20.0;
  finalize(model);
  Simulator sim(model);
  for (int k = 0; k < 20000; ++k) sim.step();
  EXPECT_LT(sim.kinetic_energy(), 1e-20);  // at rest
  const FibreBundle& b = sim.model().fibres[0];
  for (int p = 0; p < b.polylines.rows(); ++p) {
    const auto line = b.polylines.row(p);
    double length = 0.0;
    for (size_t k = 1; k < line.size(); ++k)
      length += (sim.data().x[line[k]] - sim.data().x[line[k - 1]]).norm();
    // Measured 0.817 to 0.822 l0: most of the asked 0.8 l0, the shape memory
    // holding back the rest; never below the active length (fibres do not push).
    EXPECT_GT(length, 0.8 * 0.04 - 1e-9);
    EXPECT_LT(length, 0.85 * 0.04);
  }
  const double volume = sim.component_volumes()[0];
  EXPECT_NEAR(volume, 0.04 * 0.01 * 0.01, 1e-10 * volume);
  // No external force: the centre of mass stays put.
  Vec3 c = Vec3::Zero(), c0 = Vec3::Zero();
  for (int i = 0; i < model.node_count(); ++i)
    c += model.mass[i] * sim.data().x[i], c0 += model.mass[i] * model.rest_position[i];
  EXPECT_LT((c - c0).norm(), 1e-15);
}

}  // namespace
}  // namespace phymul
