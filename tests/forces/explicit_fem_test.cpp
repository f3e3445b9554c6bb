// Explicit finite elements (TLED): frame invariance, forces as the energy's gradient, the
// patch test against the analytic Neo-Hookean stress, and static equilibrium against the
// implicit reference FEM.
#include "forces/explicit_fem.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "phymul/fem.hpp"
#include "phymul/simulation.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

constexpr double kYoung = 20e3, kPoisson = 0.3;  // Pa

MaterialSpec fem_material(double poisson = kPoisson) {
  MaterialSpec m;
  m.model = ElasticModel::fem;
  m.young = kYoung;
  m.poisson = poisson;
  m.density = 1000.0;
  return m;
}

Model block(CellType type, int n = 3, double poisson = kPoisson) {
  Model model;
  add_elastic_component(model, "block", make_box(Vec3(0.03, 0.02, 0.025), {n, n, n}, type),
                        fem_material(poisson));
  finalize(model);
  return model;
}

struct Evaluation {
  std::vector<Vec3> f;
  double energy;
};

Evaluation evaluate(const Model& model, const std::vector<Vec3>& x) {
  Evaluation out{std::vector<Vec3>(x.size(), Vec3::Zero()), 0.0};
  std::vector<double> blocks = testing::block_scratch(model.explicit_fem[0].plan);
  out.energy =
      add_explicit_fem_forces(model.explicit_fem[0], model.rest_position, x, out.f, blocks);
  return out;
}

class ExplicitFemCells : public ::testing::TestWithParam<CellType> {};

TEST_P(ExplicitFemCells, RigidMotionGivesNoForceAndNoEnergy) {
  const Model model = block(GetParam());
  std::mt19937 rng(7);
  const Eigen::Matrix3d R = testing::random_rotation(rng);
  std::vector<Vec3> x;
  for (const Vec3& p : model.rest_position) x.push_back(R * p + Vec3(0.3, -0.2, 0.1));
  const Evaluation e = evaluate(model, x);
  // Force scale: E times a cell face, 20e3 * 1e-4 = 2 N.
  for (const Vec3& f : e.f) EXPECT_LT(f.norm(), 1e-11);
  EXPECT_LT(std::abs(e.energy), 1e-15);
}

TEST_P(ExplicitFemCells, ForcesAreMinusTheEnergyGradient) {
  const Model model = block(GetParam());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  std::vector<Vec3> x = model.rest_position;
  for (Vec3& p : x) p += testing::random_vec3(u, rng);
  const Evaluation at = evaluate(model, x);
  double largest = 0.0;
  for (const Vec3& f : at.f) largest = std::max(largest, f.norm());
  const double h = 1e-7;
  for (int i = 0; i < model.node_count(); i += 5) {
    for (int d = 0; d < 3; ++d) {
      std::vector<Vec3> plus = x, minus = x;
      plus[i][d] += h;
      minus[i][d] -= h;
      const double slope = (evaluate(model, plus).energy - evaluate(model, minus).energy) / (2 * h);
      EXPECT_NEAR(at.f[i][d], -slope, 1e-6 * largest) << "node " << i << " axis " << d;
    }
  }
}

// A homogeneous deformation x = F X: every interior node is in balance and the nodes of the
// face x = +a carry P n A, P = mu J^-2/3 (F - I1/3 F^-T) + kappa J (J - 1) F^-T.
TEST_P(ExplicitFemCells, PatchTestMatchesTheAnalyticStress) {
  const Model model = block(GetParam(), 4);
  Eigen::Matrix3d F;
  F << 1.12, 0.05, 0.0, 0.02, 0.95, 0.03, 0.0, -0.04, 0.97;
  std::vector<Vec3> x;
  for (const Vec3& p : model.rest_position) x.push_back(F * p);
  const Evaluation e = evaluate(model, x);
  const double mu = kYoung / (2 * (1 + kPoisson)), kappa = kYoung / (3 * (1 - 2 * kPoisson));
  const double J = F.determinant();
  const Eigen::Matrix3d H = F.inverse().transpose();
  const Eigen::Matrix3d P =
      mu * std::pow(J, -2.0 / 3.0) * (F - F.squaredNorm() / 3.0 * H) + kappa * J * (J - 1) * H;
  const double a = 0.015, area = 0.02 * 0.025;
  Vec3 face = Vec3::Zero();
  for (int i = 0; i < model.node_count(); ++i) {
    const Vec3& p = model.rest_position[i];
    const bool boundary = std::abs(std::abs(p.x()) - 0.015) < 1e-12 ||
                          std::abs(std::abs(p.y()) - 0.01) < 1e-12 ||
                          std::abs(std::abs(p.z()) - 0.0125) < 1e-12;
    if (!boundary) {
      EXPECT_LT(e.f[i].norm(), 1e-10) << "interior node " << i;
    }
    if (std::abs(p.x() - a) < 1e-12) face += e.f[i];
  }
  // The internal forces on the face nodes are minus the traction the face needs.
  const Vec3 expected = -P * Vec3::UnitX() * area;
  EXPECT_NEAR((face - expected).norm(), 0.0, 1e-9 * expected.norm()) << face.transpose();
}

TEST_P(ExplicitFemCells, AnInvertedCellHasNoEnergyAndIsNamed) {
  const Model model = block(GetParam());
  const ExplicitFem& fem = model.explicit_fem[0];
  // Squeezed to half its height: J = 0.5 everywhere, a finite energy and no inverted cell.
  std::vector<Vec3> x = model.rest_position;
  for (Vec3& p : x) p.z() *= 0.5;
  EXPECT_TRUE(std::isfinite(evaluate(model, x).energy));
  EXPECT_EQ(first_inverted_cell(fem, model.rest_position, x).cell, -1);
  // Mirrored through z = 0: J = -1 in every cell. The forces stay finite (cbrt keeps the
  // sign), so only the energy can tell.
  for (Vec3& p : x) p.z() *= -2.0;
  const Evaluation mirrored = evaluate(model, x);
  for (const Vec3& f : mirrored.f) EXPECT_TRUE(f.allFinite());
  EXPECT_TRUE(std::isnan(mirrored.energy));
  const InvertedCell bad = first_inverted_cell(fem, model.rest_position, x);
  EXPECT_EQ(bad.cell, 0);
  EXPECT_NEAR(bad.J, -1.0, 1e-12);
  ASSERT_EQ(int(bad.nodes.size()), fem.nodes_per_cell);
  EXPECT_EQ(bad.nodes.data(), fem.cells.data());
}

// The pass's two hexahedron kernels: four cells in lanes give each cell's forces and energy as
// the cell-by-cell reference does (to round-off: the same arithmetic, lane by lane), on a
// jittered block deformed at random, a lane's inverted cell included.
TEST(ExplicitFemLanes, FourHexahedraAgreeWithTheCellByCellKernel) {
  Model model;
  add_elastic_component(
      model, "block",
      testing::jittered(make_box(Vec3(0.03, 0.02, 0.025), {4, 3, 3}, CellType::hexa), 0.006),
      fem_material(0.45));
  finalize(model);
  const ExplicitFem& fem = model.explicit_fem[0];
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.5e-3, 1.5e-3);
  std::vector<Vec3> x = model.rest_position;
  for (Vec3& p : x) p += testing::random_vec3(u, rng);
  const int cells = int(fem.volume.size());
  ASSERT_EQ(cells % 4, 0);
  for (const bool invert : {false, true}) {
    SCOPED_TRACE(invert);
    // Cell 6 (the third lane of the second four) turned inside out by its first corner
    // (its neighbours around that corner with it).
    if (invert) {
      const int* c = fem.cells.data() + 6 * 8;
      x[size_t(c[0])] = x[size_t(c[6])] + 2.0 * (x[size_t(c[6])] - x[size_t(c[0])]);
      ASSERT_GE(first_inverted_cell(fem, model.rest_position, x).cell, 0);
    }
    std::vector<Vec3> reference(x.size(), Vec3::Zero()), lanes = reference;
    double largest = 0.0;
    int inverted = 0, sound = 0;  // groups of four with an inverted cell, and without
    for (int e = 0; e < cells; e += 4) {
      double one_by_one = 0.0;
      for (int l = 0; l < 4; ++l)
        one_by_one += add_hexahedron_forces(fem, e + l, model.rest_position, x, reference);
      const double four = add_four_hexahedra_forces(fem, e, model.rest_position, x, lanes);
      if (std::isnan(one_by_one)) {
        EXPECT_TRUE(std::isnan(four)) << "cells " << e;
        ++inverted;
      } else {
        EXPECT_NEAR(four, one_by_one, 1e-13 * std::abs(one_by_one)) << "cells " << e;
        EXPECT_GT(one_by_one, 0.0);
        ++sound;
      }
    }
    EXPECT_EQ(inverted > 0, invert);
    EXPECT_GT(sound, 0);
    for (const Vec3& f : reference) largest = std::max(largest, f.norm());
    EXPECT_GT(largest, 1e-3);  // N: the deformation loads every node
    for (size_t i = 0; i < x.size(); ++i)
      EXPECT_LT((lanes[i] - reference[i]).norm(), 1e-13 * largest) << "node " << i;
  }
}

INSTANTIATE_TEST_SUITE_P(Cells, ExplicitFemCells,
                         ::testing::Values(CellType::hexa, CellType::tetra));

TEST(ExplicitFem, RejectsBadModuliAndSurfaceMeshes) {
  Model model;
  MaterialSpec m = fem_material(0.5);
  EXPECT_THROW(add_elastic_component(
                   model, "b", make_box(Vec3(0.01, 0.01, 0.01), {2, 2, 2}, CellType::hexa), m),
               std::invalid_argument);
  m = fem_material();
  m.density.reset();
  m.mass = 0.01;
  EXPECT_THROW(
      add_elastic_component(model, "s", make_ellipsoid_surface(Vec3(0.01, 0.01, 0.01), 1), m),
      std::invalid_argument);
}

// The ellipsoid's shells hold wedges: finite elements cut them into tetrahedra. A homogeneous
// deformation x = F X must then store exactly V W(F), and a rigid motion nothing.
TEST(ExplicitFemWedges, HomogeneousStretchStoresVolumeTimesEnergyDensity) {
  const Mesh shells = make_ellipsoid_volume(Vec3(0.02, 0.015, 0.015), 2, 3);
  Model model;
  add_elastic_component(model, "prostate", shells, fem_material(0.45));
  finalize(model);
  double volume = 0.0;
  for (const Cell& c : shells.cells) volume += cell_measure(shells.points, c);
  Eigen::Matrix3d F;
  F << 1.05, 0.02, 0.0, -0.01, 0.97, 0.03, 0.0, 0.01, 1.02;
  std::vector<Vec3> x;
  for (const Vec3& p : model.rest_position) x.push_back(F * p);
  const double mu = kYoung / (2 * 1.45), kappa = kYoung / (3 * (1 - 2 * 0.45));
  const double J = F.determinant();
  const double W = mu / 2 * (std::pow(J, -2.0 / 3.0) * (F.transpose() * F).trace() - 3) +
                   kappa / 2 * (J - 1) * (J - 1);
  EXPECT_NEAR(evaluate(model, x).energy, volume * W, 1e-9 * volume * W);
  std::mt19937 rng(3);
  const Eigen::Matrix3d R = testing::random_rotation(rng);
  for (size_t i = 0; i < x.size(); ++i) x[i] = R * model.rest_position[i];
  for (const Vec3& f : evaluate(model, x).f) EXPECT_LT(f.norm(), 1e-11);
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// A 40 mm cube of n^3 cells, base held, top pushed down 4 mm without slip: the top reaction
// of the explicit elements relaxed to equilibrium, and of the implicit reference FEM.
struct Compression {
  double explicit_force, reference_force;
  double explicit_bulge, reference_bulge;  // m, x displacement of the mid-height corner
};

Compression compress(CellType type, int n) {
  const Mesh mesh = make_box(Vec3(0.04, 0.04, 0.04), {n, n, n}, type);
  const auto& top = mesh.node_sets.at("top");
  const auto& bottom = mesh.node_sets.at("bottom");
  int corner = 0;  // the node at (+x, +y) mid-height... the nearest one
  for (int i = 0; i < int(mesh.points.size()); ++i)
    if ((mesh.points[i] - Vec3(0.02, 0.02, 0.0)).norm() <
        (mesh.points[corner] - Vec3(0.02, 0.02, 0.0)).norm())
      corner = i;

  Model model;
  add_elastic_component(model, "cube", mesh, fem_material());
  add_fixed_nodes(model, bottom);
  add_prescribed_displacement(
      model, {top, {true, true, true}, Schedule{{0.0, 1.0}, {Vec3::Zero(), Vec3(0, 0, -0.004)}}});
  model.settings.mode = SolveMode::static_equilibrium;
  model.settings.load_steps = 2;
  model.settings.tolerance = 1e-9;  // N, against a top force of about 0.8 N
  finalize(model);
  Simulator sim(model);
  const StaticResult r = sim.solve_static();
  EXPECT_TRUE(r.converged) << r.residual;
  const std::vector<Vec3> reaction = sim.support_reactions();
  Compression out{};
  for (int i : top) out.explicit_force -= reaction[i].z();  // the plate pushes down
  out.explicit_bulge = sim.data().x[corner].x() - mesh.points[corner].x();

  fem::Problem problem;
  problem.mesh = mesh;
  problem.material = {fem::Law::neo_hookean, kYoung, kPoisson};
  for (int i : bottom)
    for (int a = 0; a < 3; ++a) problem.prescribed.push_back({i, a, 0.0});
  for (int i : top)
    for (int a = 0; a < 3; ++a) problem.prescribed.push_back({i, a, a == 2 ? -0.004 : 0.0});
  problem.load_steps = 2;
  const fem::Result solved = fem::solve_static(problem);
  EXPECT_TRUE(solved.converged) << solved.message;
  for (int i : top) out.reference_force -= solved.reaction[i].z();
  out.reference_bulge = solved.displacement[corner].x();
  return out;
}

// A 10 mm cube of 2^3 hexahedra, base held, its top driven down through the base in 0.1 s:
// the step that inverts a cell is undone, and the error names that cell.
TEST(ExplicitFem, DynamicsStopAtTheFirstInvertedCellAndKeepTheLastGoodState) {
  const Mesh mesh = make_box(Vec3(0.01, 0.01, 0.01), {2, 2, 2}, CellType::hexa);
  Model model;
  add_elastic_component(model, "cube", mesh, fem_material());
  add_fixed_nodes(model, mesh.node_sets.at("bottom"));
  add_prescribed_displacement(model, {mesh.node_sets.at("top"),
                                      {true, true, true},
                                      Schedule{{0.0, 0.1}, {Vec3::Zero(), Vec3(0, 0, -0.015)}}});
  model.settings.duration = 0.2;
  finalize(model);
  Simulator sim(model);
  const ExplicitFem& fem = sim.model().explicit_fem[0];
  std::string message;
  double when = -1.0;
  try {
    while (sim.data().time < 0.2) sim.step();
  } catch (const InstabilityError& e) {
    message = e.what();
    when = e.time;
  }
  ASSERT_FALSE(message.empty()) << "the top went through the base without an error";
  std::printf("%s\n", message.c_str());
  EXPECT_NE(message.find("finite-element cell of component 'cube' is inverted"), std::string::npos);
  // Not before the top has come down by a layer (5 mm, at 1/30 s), nor after it passed the base.
  EXPECT_GT(when, 0.1 / 3.0);
  EXPECT_LT(when, 0.1 * 10.0 / 15.0 + 1e-9);
  // The state kept is the step before: every cell upright, its energy finite (what a run
  // writes), at the time before the failing step.
  EXPECT_EQ(first_inverted_cell(fem, sim.model().rest_position, sim.data().x).cell, -1);
  EXPECT_TRUE(std::isfinite(sim.data().shape_memory_energy));
  EXPECT_NEAR(sim.data().time, when - sim.dt(), 1e-12);
}

TEST(ExplicitFem, CompressedCubeMatchesTheImplicitReference) {
  // Tetrahedra: the same discretisation as the reference (one point, constant strain), so
  // the same equilibrium, to the relaxation tolerance.
  for (int n : {4, 8}) {
    const Compression c = compress(CellType::tetra, n);
    EXPECT_NEAR(c.explicit_force, c.reference_force, 1e-6 * c.reference_force) << n;
    EXPECT_NEAR(c.explicit_bulge, c.reference_bulge, 1e-5 * c.reference_bulge) << n;
  }
  // Hexahedra: one point and hourglass control against 2x2x2 points and mean dilatation.
  // Measured: force 0.33 % (4^3) and 0.07 % (8^3) above, bulge 0.2 % and 0.2 %; the gap
  // closes as the mesh is refined.
  double previous_gap = 1.0;
  for (int n : {4, 8}) {
    const Compression c = compress(CellType::hexa, n);
    const double gap = std::abs(c.explicit_force / c.reference_force - 1.0);
    std::printf("hexa %d^3: top force %.6g N (reference %.6g N), bulge %.4g mm (%.4g mm)\n", n,
                c.explicit_force, c.reference_force, c.explicit_bulge * 1e3,
                c.reference_bulge * 1e3);
    EXPECT_LT(gap, 5e-3) << n;
    EXPECT_NEAR(c.explicit_bulge, c.reference_bulge, 6e-3 * c.reference_bulge) << n;
    EXPECT_LT(gap, previous_gap) << n;
    previous_gap = gap;
  }
}

}  // namespace
}  // namespace phymul
