#include "phymul/calibration.hpp"

#include <gtest/gtest.h>

namespace phymul::calibration {
namespace {

TEST(Calibration, MeanEdgeLengthOfAUnitHexaGridIsOneOverN) {
  for (int n : {1, 2, 3, 5, 8}) {
    const Mesh mesh = make_box(Vec3::Ones(), {n, n, n}, CellType::hexa, Vec3::Constant(0.5));
    // 1/n up to the rounding of the generated coordinates (1.8e-15 measured at n = 5).
    EXPECT_NEAR(mean_edge_length(mesh), 1.0 / n, 1e-14) << n;
  }
  // Tetrahedra (6 per cube) add face and body diagonals: longer on average.
  const Mesh tets = make_box(Vec3::Ones(), {2, 2, 2}, CellType::tetra);
  EXPECT_GT(mean_edge_length(tets), 0.5);
  EXPECT_THROW(mean_edge_length(Mesh{}), std::invalid_argument);
}

// (a) With the calibrated alpha the shape-memory top force equals the FEM one at the
// calibration strain (the LSM force is linear in K; only the relaxation tolerance remains).
TEST(Calibration, CalibratedStiffnessReproducesTheFemTopForce) {
  for (CellType type : {CellType::hexa, CellType::tetra}) {
    const Compression c = calibrate_compression(type, 4);
    EXPECT_GT(c.fem_force, 0.0);
    EXPECT_NEAR(c.lsm_force, c.fem_force, 1e-9 * c.fem_force) << cell_type_name(type);
    EXPECT_GT(c.alpha, 0.0);
  }
}

// (b) Mesh (in)dependence of alpha, measured: K = alpha E h is NOT mesh-independent for the
// shape memory. From 4 to 8 cells per 40 mm edge alpha grows by 4.45 on hexahedra (4.522 ->
// 20.12) and 3.35 on tetrahedra (2.422 -> 8.119), about h^-2 on hexahedra: the shape memory
// with reaction hardly resists a uniform strain (an affine field leaves an interior node on
// its attraction position), so the force of the bonded compression comes from the
// volume constraint and the non-uniform strain near the plates. This test pins that finding
// so a change of the model that fixes (or worsens) it shows up.
TEST(Calibration, AlphaIsNotMeshIndependentMeasuredRatio) {
  const Compression h4 = calibrate_compression(CellType::hexa, 4);
  const Compression h8 = calibrate_compression(CellType::hexa, 8);
  // Halving h multiplies alpha by about (h4/h8)^2 = 4 (measured 4.45): K ~ E L^2 / h, the
  // stiffness of a strain-gradient energy, not of a local one.
  EXPECT_GT(h8.alpha / h4.alpha, 3.0);
  EXPECT_LT(h8.alpha / h4.alpha, 6.0);
  const Compression t4 = calibrate_compression(CellType::tetra, 4);
  const Compression t8 = calibrate_compression(CellType::tetra, 8);
  EXPECT_GT(t8.alpha / t4.alpha, 2.5);  // measured 3.35
  EXPECT_LT(t8.alpha / t4.alpha, 6.0);
  // The FEM top force itself is mesh-converged within 2 % on hexahedra (nu 0.499).
  EXPECT_NEAR(h8.fem_force, h4.fem_force, 0.02 * h4.fem_force);
}

// (c) A different load with the alpha calibrated on the same mesh: 80 x 20 x 20 mm
// cantilever under gravity (E 500 kPa, FEM tip about 2.9 mm on hexahedra, Euler-Bernoulli
// 3.0 mm). Measured on 4 cells per 40 mm: the shape memory's tip deflection is 0.403 of the
// FEM one on hexahedra (too stiff by 2.5x) and 1.44 of it on tetrahedra (whose FEM, linear
// tetrahedra at nu 0.45 on 2 cells across, is itself 3x stiffer than Euler-Bernoulli).
// At 8 cells the ratios are 0.73 (hexa) and 1.84 (tetra): not a converging agreement.
TEST(Calibration, CantileverTipWithCalibratedAlphaWithinMeasuredFactor) {
  const Compression h = calibrate_compression(CellType::hexa, 4);
  const Cantilever ch = check_cantilever(CellType::hexa, 4, h.alpha);
  // The reference itself: hexahedral FEM against beam theory.
  EXPECT_NEAR(ch.fem_tip, ch.euler_bernoulli_tip, 0.1 * ch.euler_bernoulli_tip);
  const Compression t = calibrate_compression(CellType::tetra, 4);
  const Cantilever ct = check_cantilever(CellType::tetra, 4, t.alpha);
  // Within a factor 2.5 of the FEM either way, no better.
  for (const Cantilever& c : {ch, ct}) {
    EXPECT_GT(c.tip_ratio, 1.0 / 2.5);
    EXPECT_LT(c.tip_ratio, 2.5);
  }
}

TEST(Calibration, TableAndJsonListEveryRow) {
  Options o;
  o.cantilever = false;
  const Result r = run({CellType::hexa}, {2}, o);
  ASSERT_EQ(r.rows.size(), 1u);
  EXPECT_NE(table(r).find("hexa"), std::string::npos);
  EXPECT_NE(json(r).find("\"alpha\": "), std::string::npos);
  EXPECT_THROW(calibrate_compression(CellType::wedge, 2), std::invalid_argument);
}

}  // namespace
}  // namespace phymul::calibration
