// The Truth Cube load case: an 80 mm cube (E = 14.9 kPa) compressed between plates that hold
// without slip. Checks that nu = 0.499 does not lock on hexahedra, mesh convergence, volume
// conservation, and pins the reference values the shape-memory model is validated against.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "fem/fem_test_util.hpp"

namespace phymul {
namespace {

using fem_test::bonded_compression;
using fem_test::kCubeSize;

// Plate force (N, positive in compression) of the bonded cube.
double plate_force(int cells, double strain, double poisson, CellType type = CellType::hexa,
                   int load_steps = 2) {
  fem::Problem p = bonded_compression(cells, strain, poisson, type, load_steps);
  const fem::Result r = fem::solve_static(p);
  EXPECT_TRUE(r.converged) << r.message;
  // The plates push the cube: downwards on the top, upwards on the bottom, equally.
  const double top = -fem_test::set_reaction(r, p.mesh.node_sets["top"], 2);
  EXPECT_NEAR(fem_test::set_reaction(r, p.mesh.node_sets["bottom"], 2), top, 1e-8 * top);
  return top;
}

// A locking element stiffens as nu -> 0.5 (x2-3 between 0.49 and 0.499, like the tetrahedra
// below). With mean dilatation the force changes by the small physical amount due to the
// bonded faces' constraint: measured 6.3224 N against 6.2542 N (+1.1 %).
TEST(FemBondedCompression, HexahedraDoNotLockAtNuPoint499) {
  const double f499 = plate_force(8, 0.05, 0.499);
  const double f49 = plate_force(8, 0.05, 0.49);
  EXPECT_GT(f499 / f49, 1.0);
  EXPECT_LT(f499 / f49, 1.03);
  // The unconfined uniaxial value E A strain = 4.77 N is a lower bound; bonding adds ~1/3.
  const double uniaxial = fem_test::kCubeYoung * kCubeSize * kCubeSize * 0.05;
  EXPECT_GT(f499, 1.2 * uniaxial);
  EXPECT_LT(f499, 1.5 * uniaxial);
}

// Documents the known limitation: linear tetrahedra (one J per cell) do lock. At nu = 0.499
// they give 16.5 N (x2.6 the hexahedral value), while at nu = 0.3 they agree with hexahedra
// to ~1 % (5.43 N against 5.37 N).
TEST(FemBondedCompression, LinearTetrahedraLockButAgreeWithHexahedraAtNuPoint3) {
  EXPECT_GT(
      plate_force(8, 0.05, 0.499, CellType::tetra) / plate_force(8, 0.05, 0.49, CellType::tetra),
      1.5);
  const double tet = plate_force(8, 0.05, 0.3, CellType::tetra);
  const double hex = plate_force(8, 0.05, 0.3, CellType::hexa);
  EXPECT_NEAR(tet / hex, 1.0, 0.03);
}

// 8^3 against 16^3 hexahedra at 5 %: 6.3224 N against 6.2554 N (1.07 %; 12^3 gives 6.2786 N,
// converging from above as an element without locking should).
TEST(FemBondedCompression, TopForceIsMeshConvergedWithinTwoPercent) {
  const double coarse = plate_force(8, 0.05, 0.499);
  const double fine = plate_force(16, 0.05, 0.499);
  EXPECT_GT(coarse, fine);
  EXPECT_NEAR(coarse / fine, 1.0, 0.02);
}

// At 18.25 % compression, nu = 0.499 (kappa/mu = 500): the deformed volume, measured as the
// sum of the mesh module's cell volumes at the deformed nodes (faces triangulated, so this is
// also the volume enclosed by the deformed boundary), stays within 0.5 % of 80^3 mm^3. The
// mean pressure of ~1 kPa over kappa = 2.5 MPa predicts a change of a few 1e-4.
TEST(FemBondedCompression, VolumeIsConservedAtNuPoint499) {
  fem::Problem p = bonded_compression(8, 0.1825, 0.499);
  const fem::Result r = fem::solve_static(p);
  ASSERT_TRUE(r.converged) << r.message;
  const double initial = fem_test::total_volume(p.mesh.points, p.mesh);
  const double deformed = fem_test::total_volume(fem_test::deformed_points(p.mesh, r), p.mesh);
  EXPECT_NEAR(initial, std::pow(kCubeSize, 3), 1e-12);
  const double change = deformed / initial - 1.0;
  RecordProperty("relative_volume_change", std::to_string(change));
  std::printf("[ truth cube ] 18.25 %% volume change: %.3e\n", change);
  EXPECT_LT(std::abs(change), 5e-3);
  EXPECT_LT(change, 0.0);  // compression: the pressure is positive, the volume shrinks a little
}

// Reference values of this solver for the Truth Cube (8^3 hexahedra, nu = 0.499, 10 load
// steps), pinned to catch unintended changes; they are to be cross-checked with CalculiX.
// Also the speed target: well under 2 s for the 18.25 % case (about 0.5 s at -O2 here).
TEST(FemBondedCompression, TruthCubeReferenceForces) {
  const std::array<std::pair<double, double>, 3> cases{
      {{0.05, 6.322369615}, {0.125, 17.25459353}, {0.1825, 27.07088162}}};
  for (const auto& [strain, force] : cases) {
    fem::Problem p = bonded_compression(8, strain, 0.499);
    const auto start = std::chrono::steady_clock::now();
    const fem::Result r = fem::solve_static(p);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_TRUE(r.converged) << r.message;
    const double top = -fem_test::set_reaction(r, p.mesh.node_sets["top"], 2);
    EXPECT_NEAR(top, force, 1e-8 * force) << "strain " << strain;
    EXPECT_LE(r.newton_iterations, 3 * p.load_steps);
    EXPECT_LT(seconds, 10.0);  // generous: shared machines; the target is < 2 s
    std::printf("[ truth cube ] %.2f %% : %.10g N, %d Newton iterations, %.3f s\n", 100 * strain,
                top, r.newton_iterations, seconds);
  }
}

}  // namespace
}  // namespace phymul
