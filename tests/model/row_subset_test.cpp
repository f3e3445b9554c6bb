// RowSubset, and the shape memory's per-node data kept only for the nodes that use them.
#include "model/row_subset.hpp"

#include <gtest/gtest.h>

#include <random>

#include "support/models.hpp"

namespace phymul {
namespace {

TEST(RowSubset, FindGivesEachMemberItsRankAndMinusOneToOthers) {
  std::mt19937 rng(7);
  for (size_t rows : {0, 1, 63, 64, 65, 1000}) {
    for (double share : {0.0, 0.01, 0.5, 1.0}) {
      std::bernoulli_distribution member(share);
      std::vector<char> in(rows);
      for (char& c : in) c = member(rng) ? 1 : 0;
      const RowSubset s = make_row_subset(in);
      int rank = 0;
      for (size_t k = 0; k < rows; ++k) {
        ASSERT_EQ(s.find(int(k)), in[k] ? rank : -1) << rows << " rows, row " << k;
        rank += in[k];
      }
    }
  }
}

// A corner of a box has three neighbours, always in a plane: its normal pair weighs the mean
// squared distance of the three from their centroid, 2/9 (hx^2 + hy^2 + hz^2). No other node
// of a box is flat, so the corners alone keep a weight and a frame pair.
TEST(ShapeMemoryLayout, PolarBoxKeepsNormalPairsForItsCornersOnly) {
  const Vec3 size(0.03, 0.02, 0.025);
  const std::array<int, 3> cells{3, 2, 4};
  const Model model =
      testing::single_component(make_box(size, cells, CellType::hexa), testing::material(50.0));
  const ShapeMemory& m = model.shape_memory[0];
  const Vec3 h = size.cwiseQuotient(Vec3(cells[0], cells[1], cells[2]));
  const Vec3 lo = -0.5 * size, hi = 0.5 * size;
  int corners = 0;
  for (int k = 0; k < int(m.nodes.size()); ++k) {
    const Vec3& p = model.rest_position[m.nodes[k]];
    bool corner = true;
    for (int a = 0; a < 3; ++a)
      corner = corner && (std::abs(p[a] - lo[a]) < 1e-12 || std::abs(p[a] - hi[a]) < 1e-12);
    const int f = m.framed.find(k);
    EXPECT_EQ(f >= 0, corner) << "node " << m.nodes[k];
    if (f < 0) continue;
    EXPECT_EQ(f, corners);
    EXPECT_NEAR(m.normal_weight[f], 2.0 / 9.0 * h.squaredNorm(), 1e-15);
    ++corners;
  }
  EXPECT_EQ(corners, 8);
  EXPECT_EQ(m.normal_weight.size(), 8u);
  EXPECT_EQ(m.frame_pair.size(), 8u);
  EXPECT_TRUE(m.rest_offset.empty());  // recomputed in polar mode
}

TEST(ShapeMemoryLayout, FrameModeKeepsFramePairsAndRestOffsetsForEveryNode) {
  const Model model =
      testing::single_component(make_box(Vec3(0.03, 0.02, 0.025), {3, 2, 4}, CellType::hexa),
                                testing::material(50.0, FrameMode::frame));
  const ShapeMemory& m = model.shape_memory[0];
  for (int k = 0; k < int(m.nodes.size()); ++k) EXPECT_EQ(m.framed.find(k), k);
  EXPECT_EQ(m.frame_pair.size(), m.nodes.size());
  EXPECT_EQ(m.rest_offset.size(), m.nodes.size());
}

TEST(ShapeMemoryLayout, SurfaceKeepsNormalWeightsForEveryNodeAndNoFramePairs) {
  const Model model =
      testing::single_component(make_ellipsoid_surface({0.02, 0.015, 0.01}, 2),
                                testing::surface_material(50.0, 0.1, FrameMode::polar));
  const ShapeMemory& m = model.shape_memory[0];
  ASSERT_EQ(m.normal_weight.size(), m.nodes.size());
  for (int k = 0; k < int(m.nodes.size()); ++k) {
    EXPECT_EQ(m.framed.find(k), k);
    EXPECT_GT(m.normal_weight[k], 0.0);
  }
  EXPECT_TRUE(m.frame_pair.empty());  // surface frames come from the ordered ring
}

}  // namespace
}  // namespace phymul
