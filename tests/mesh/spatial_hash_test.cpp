// The triangle hash's broad phase far from the origin: cells past 2^52 are clamped, so a
// surface whose coordinates are huge against its triangles still finds its neighbours and
// no cell index overflows (a fuzzed NIfTI frame once placed a label 5e36 m away).
#include "mesh/spatial_hash.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <vector>

namespace phymul {
namespace {

constexpr std::int64_t kLimit = std::int64_t(1) << 52;

TEST(TriangleHash, CellsFarAwayOrNotFiniteAreTheBoundingCells) {
  TriangleHash hash;
  const std::vector<Vec3> x{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<Triangle> t{{0, 1, 2}};
  hash.reserve(t.size());
  hash.build(t, x, 0.0);
  EXPECT_EQ(hash.cell_of({1e300, -1e300, 0.5}), (TriangleHash::Cell{kLimit, -kLimit, 0}));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(hash.cell_of({nan, 2.5, -2.5})[0], -kLimit);
}

TEST(TriangleHash, NeighboursFarFromTheOriginAreFoundAround) {
  // Two triangles a millimetre apart, 1e30 m out along x: 1e33 cells from the origin.
  const double far = 1e30;
  std::vector<Vec3> x;
  for (double dz : {0.0, 1e-3})
    for (const Vec3& p : {Vec3(far, 0, dz), Vec3(far * (1 + 1e-15), 0, dz), Vec3(far, 1e-3, dz)})
      x.push_back(p);
  const std::vector<Triangle> t{{0, 1, 2}, {3, 4, 5}};
  TriangleHash hash;
  hash.reserve(t.size());
  hash.build(t, x, 1e-3);
  std::set<int> found;
  hash.around(x[0], [&](int k) { found.insert(k); });
  EXPECT_EQ(found, (std::set<int>{0, 1}));
}

}  // namespace
}  // namespace phymul
