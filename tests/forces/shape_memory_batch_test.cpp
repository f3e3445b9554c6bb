#include "forces/shape_memory_batch.hpp"

#include <gtest/gtest.h>

#include <random>

#include "forces/shape_memory.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

constexpr int W = kShapeMemoryLanes;

// A 3 cm block of 6^3 hexahedra, K = 50 N/m, its nodes jittered so that every one takes the
// lanes (a regular grid's interior nodes are centred: regular_block).
Model block() {
  return testing::single_component(
      testing::jittered(make_box(Vec3(0.03, 0.03, 0.03), {6, 6, 6}, CellType::hexa), 0.005),
      testing::material(50.0));
}

Model regular_block() {
  return testing::single_component(make_box(Vec3(0.03, 0.03, 0.03), {6, 6, 6}, CellType::hexa),
                                   testing::material(50.0));
}

// The block turned by a random rotation, bent and shaken (0.5 mm noise on 5 mm cells), with
// rotations that start converged but for a small turn (the lanes' case) or from the identity,
// far from the node's best fit (the scalar fallback's case).
struct Deformed {
  std::vector<Vec3> x;
  std::vector<Eigen::Quaterniond> rotations;
};

Deformed deformed(const Model& model, std::mt19937& rng) {
  const ShapeMemory& m = model.shape_memory[0];
  const Eigen::Matrix3d R = testing::random_rotation(rng);
  std::uniform_real_distribution<double> noise(-5e-4, 5e-4);
  Deformed d;
  for (const Vec3& X : model.rest_position) {
    const Vec3 bent(X.x() + 4.0 * X.z() * X.z(), X.y() * (1.0 + 5.0 * X.x()), 0.9 * X.z());
    d.x.push_back(R * bent + testing::random_vec3(noise, rng));
  }
  std::uniform_int_distribution<int> cold(0, 4);
  for (int k = 0; k < int(m.nodes.size()); ++k) {
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    attraction_position(m, k, model.rest_position, d.x, q);  // converged
    d.rotations.push_back(cold(rng) == 0 ? Eigen::Quaterniond::Identity()
                                         : q * testing::small_turn(rng, 0.02));
  }
  return d;
}

double largest(std::span<const Vec3> f) {
  double m = 0.0;
  for (const Vec3& v : f) m = std::max(m, v.norm());
  return m;
}

TEST(ShapeMemoryBatch, PlanBatchesEqualCountsAndNormalPairs) {
  const Model model = block();
  const ShapeMemory& m = model.shape_memory[0];
  ASSERT_EQ(m.batch_order.size(), m.nodes.size());
  ASSERT_EQ(int(m.batched_end.size()), m.plan.blocks());
  int batched = 0;
  for (int b = 0; b < m.plan.blocks(); ++b) {
    const int start = m.plan.block_start[b], end = m.plan.block_start[b + 1];
    std::vector<int> block(m.batch_order.begin() + start, m.batch_order.begin() + end);
    std::sort(block.begin(), block.end());
    for (int k = start; k < end; ++k) EXPECT_EQ(block[size_t(k - start)], k);  // a permutation
    ASSERT_EQ((m.batched_end[b] - start) % W, 0);
    for (int p = start; p < m.batched_end[b]; p += W)
      for (int l = 0; l < W; ++l) {
        const int k = m.batch_order[size_t(p + l)];
        const int first = m.batch_order[size_t(p)];
        EXPECT_EQ(m.framed.find(k) >= 0, m.framed.find(first) >= 0) << "node " << k;
        EXPECT_EQ(m.neighbours.row(k).size(), m.neighbours.row(m.batch_order[size_t(p)]).size());
      }
    batched += m.batched_end[b] - start;
  }
  // 7^3 nodes: the 8 corners carry the normal pair of their frame (in lanes too); at most 3 a
  // neighbour count are left over.
  EXPECT_GE(batched, 343 - 3 * 3);
  int corners = 0;
  for (int b = 0; b < m.plan.blocks(); ++b)
    for (int p = m.plan.block_start[b]; p < m.batched_end[b]; ++p)
      corners += m.framed.find(m.batch_order[size_t(p)]) >= 0;
  EXPECT_GE(corners, 4);  // a batch of corners at least (a block leaves up to 3 over)
}

// The whole pass and every node on the scalar path, from the same deformed state.
struct PassAndScalar {
  std::vector<Vec3> f_scalar, f_pass;
  std::vector<Eigen::Quaterniond> q_scalar, q_pass;
  double e_scalar = 0.0, e_pass = 0.0;
};

PassAndScalar pass_and_scalar(const Model& model, const Deformed& d) {
  const ShapeMemory& m = model.shape_memory[0];
  PassAndScalar r{std::vector<Vec3>(d.x.size(), Vec3::Zero()),
                  std::vector<Vec3>(d.x.size(), Vec3::Zero()), d.rotations, d.rotations};
  for (int k = 0; k < int(m.nodes.size()); ++k)
    r.e_scalar += add_polar_node_forces(m, k, model.rest_position, d.x, r.q_scalar, r.f_scalar);
  std::vector<double> blocks = testing::block_scratch(m.plan);
  r.e_pass = add_shape_memory_forces(m, model.rest_position, d.x, r.q_pass, r.f_pass, blocks);
  return r;
}

// The whole batched pass against every node on the scalar path; both kinds of lanes occur.
void expect_agreement(const Model& model, std::mt19937& rng) {
  const ShapeMemory& m = model.shape_memory[0];
  const Deformed d = deformed(model, rng);
  const auto [f_scalar, f_batch, q_scalar, q_batch, e_scalar, e_batch] = pass_and_scalar(model, d);
  const double scale = largest(f_scalar);
  ASSERT_GT(scale, 1e-3);  // N: a real deformation
  for (size_t i = 0; i < d.x.size(); ++i)
    EXPECT_LE((f_batch[i] - f_scalar[i]).norm(), 1e-12 * scale) << "node " << i;
  EXPECT_NEAR(e_batch, e_scalar, 1e-12 * e_scalar);
  for (size_t k = 0; k < q_scalar.size(); ++k)
    EXPECT_LE((q_batch[k].coeffs() - q_scalar[k].coeffs()).norm(), 1e-12) << "node " << k;

  int in_lanes = 0, fell_back = 0;
  std::vector<Vec3> f(d.x.size(), Vec3::Zero());
  std::vector<Eigen::Quaterniond> q = d.rotations;
  for (int b = 0; b < m.plan.blocks(); ++b)
    for (int p = m.plan.block_start[b]; p < m.batched_end[b]; p += W) {
      std::array<int, W> ks;
      std::copy_n(m.batch_order.begin() + p, W, ks.begin());
      std::array<bool, W> batched;
      add_polar_batch_forces(m, ks, model.rest_position, d.x, q, f, &batched);
      for (bool lane : batched) (lane ? in_lanes : fell_back) += 1;
    }
  EXPECT_GT(in_lanes, 2 * fell_back);
  EXPECT_GT(fell_back, 5);
}

TEST(ShapeMemoryBatch, AgreesWithTheScalarPathIncludingFallbacks) {
  const Model model = block();
  std::mt19937 rng(11);
  for (int trial = 0; trial < 5; ++trial) expect_agreement(model, rng);
}

// Surface nodes carry the normal pair of their ordered ring: batched too.
TEST(ShapeMemoryBatch, SurfaceNodesAgreeWithTheScalarPath) {
  const Model model =
      testing::single_component(make_ellipsoid_surface({0.02, 0.015, 0.01}, 3),
                                testing::surface_material(50.0, 0.1, FrameMode::polar));
  const ShapeMemory& m = model.shape_memory[0];
  ASSERT_TRUE(m.surface);
  int batched = 0;
  for (int b = 0; b < m.plan.blocks(); ++b) batched += m.batched_end[b] - m.plan.block_start[b];
  // Rings of 5 and 6: at most 3 of each left over per block.
  EXPECT_GE(batched, int(m.nodes.size()) - 2 * 3 * m.plan.blocks());
  std::mt19937 rng(13);
  for (int trial = 0; trial < 5; ++trial) expect_agreement(model, rng);
}

// Two batches side by side give what two single batches give, bit for bit: their turns are
// interleaved, nothing else (the scalar fallbacks included, in the same order).
TEST(ShapeMemoryBatch, PairOfBatchesEqualsTwoBatches) {
  const Model model = block();
  const ShapeMemory& m = model.shape_memory[0];
  std::mt19937 rng(17);
  for (int trial = 0; trial < 3; ++trial) {
    const Deformed d = deformed(model, rng);
    std::vector<Vec3> f_single(d.x.size(), Vec3::Zero()), f_pair = f_single;
    std::vector<Eigen::Quaterniond> q_single = d.rotations, q_pair = d.rotations;
    double e_single = 0.0, e_pair = 0.0;
    int pairs = 0, fell_back = 0;
    for (int b = 0; b < m.plan.blocks(); ++b)
      for (int p = m.plan.block_start[b]; p + 2 * W <= m.batched_end[b]; p += 2 * W, ++pairs) {
        for (int half = 0; half < 2; ++half) {
          std::array<int, W> ks;
          std::copy_n(m.batch_order.begin() + p + half * W, W, ks.begin());
          std::array<bool, W> batched;
          e_single +=
              add_polar_batch_forces(m, ks, model.rest_position, d.x, q_single, f_single, &batched);
          for (bool lane : batched) fell_back += !lane;
        }
        add_polar_batch_pair_forces(m, m.batch_order.data() + p, model.rest_position, d.x, q_pair,
                                    f_pair, e_pair);
      }
    ASSERT_GT(pairs, 20);
    EXPECT_GT(fell_back, 5);  // some lanes of the pairs went the scalar way
    EXPECT_EQ(e_pair, e_single);
    for (size_t i = 0; i < d.x.size(); ++i) EXPECT_EQ(f_pair[i], f_single[i]) << "node " << i;
    for (size_t k = 0; k < q_pair.size(); ++k)
      EXPECT_EQ(q_pair[k].coeffs(), q_single[k].coeffs()) << "memory node " << k;
  }
}

TEST(ShapeMemoryBatch, ZeroForceUnderARigidRotation) {
  const Model surface =
      testing::single_component(make_ellipsoid_surface({0.02, 0.015, 0.01}, 3),
                                testing::surface_material(50.0, 0.1, FrameMode::polar));
  const Model volume = block();
  for (const Model* model : {&volume, &surface}) {
    const ShapeMemory& m = model->shape_memory[0];
    std::mt19937 rng(5);
    for (int trial = 0; trial < 10; ++trial) {
      const Eigen::Matrix3d R = testing::random_rotation(rng);
      const Vec3 t(0.1, -0.2, 0.05);
      std::vector<Vec3> x;
      for (const Vec3& X : model->rest_position) x.push_back(R * X + t);
      // Warm rotations a little off the true one: the lanes turn them back.
      std::vector<Eigen::Quaterniond> q;
      for (size_t k = 0; k < m.nodes.size(); ++k)
        q.push_back(Eigen::Quaterniond(R) * testing::small_turn(rng, 1e-3));
      std::vector<Vec3> f(x.size(), Vec3::Zero());
      int in_lanes = 0, lanes = 0;
      for (int b = 0; b < m.plan.blocks(); ++b)
        for (int p = m.plan.block_start[b]; p < m.batched_end[b]; p += W) {
          std::array<int, W> ks;
          std::copy_n(m.batch_order.begin() + p, W, ks.begin());
          std::array<bool, W> batched;
          add_polar_batch_forces(m, ks, model->rest_position, x, q, f, &batched);
          for (int l = 0; l < W; ++l) {
            in_lanes += batched[size_t(l)], ++lanes;
            const double angle = q[size_t(ks[size_t(l)])].angularDistance(Eigen::Quaterniond(R));
            EXPECT_LT(angle, 1e-12) << "node " << ks[size_t(l)];
          }
        }
      EXPECT_EQ(in_lanes, lanes);
      EXPECT_GT(lanes, 300);
      // K = 50 N/m on 5 mm cells: round-off forces are ~1e-16 N.
      EXPECT_LT(largest(f), 1e-13);
    }
  }
}

// A regular grid's interior nodes sit at their neighbours' centroid: their pull needs no fit
// and no rotation. The plan finds exactly those, and no node of an irregular mesh or a
// curved surface.
TEST(ShapeMemoryCentred, ARegularGridsInteriorNodesAndNoOthers) {
  const Model regular = regular_block();
  const ShapeMemory& m = regular.shape_memory[0];
  ASSERT_EQ(int(m.centred_start.size()), m.plan.blocks());
  Vec3 low = regular.rest_position[0], high = low;
  for (const Vec3& X : regular.rest_position) low = low.cwiseMin(X), high = high.cwiseMax(X);
  int centred = 0;
  for (int b = 0; b < m.plan.blocks(); ++b) {
    ASSERT_LE(m.batched_end[b], m.centred_start[b]);
    for (int p = m.plan.block_start[b]; p < m.plan.block_start[b + 1]; ++p) {
      const int k = m.batch_order[size_t(p)];
      const Vec3 X = regular.rest_position[m.nodes[k]];
      const bool interior =
          (X.array() > low.array() + 1e-9).all() && (X.array() < high.array() - 1e-9).all();
      const bool in_range = p >= m.centred_start[b];
      EXPECT_EQ(in_range, interior) << "node " << k;
      EXPECT_EQ(is_centred(m, k, regular.rest_position), interior) << "node " << k;
      centred += in_range;
    }
  }
  EXPECT_EQ(centred, 5 * 5 * 5);
  const Model surface =
      testing::single_component(make_ellipsoid_surface({0.02, 0.02, 0.02}, 3),
                                testing::surface_material(50.0, 0.1, FrameMode::polar));
  const Model irregular = block();
  for (const Model* model : {&surface, &irregular}) {
    const ShapeMemory& other = model->shape_memory[0];
    for (int b = 0; b < other.plan.blocks(); ++b)
      EXPECT_EQ(other.centred_start[b], other.plan.block_start[b + 1]);
  }
}

// The whole pass on the regular block against every node on the scalar path: the centred
// nodes drop R c with |c| below 64 epsilons of h, so forces agree to (n + 1) 2 K |c| at most;
// their rotations are left as they were, the others' agree.
TEST(ShapeMemoryCentred, PassAgreesWithTheScalarPath) {
  const Model model = regular_block();
  const ShapeMemory& m = model.shape_memory[0];
  std::mt19937 rng(17);
  for (int trial = 0; trial < 3; ++trial) {
    const Deformed d = deformed(model, rng);
    const auto [f_scalar, f_pass, q_scalar, q_pass, e_scalar, e_pass] = pass_and_scalar(model, d);
    const double h = 0.005, bound = 2.0 * 7.0 * 50.0 * 64.0 * 2.2204460492503131e-16 * h;
    double worst = 0.0;
    for (size_t i = 0; i < d.x.size(); ++i)
      worst = std::max(worst, (f_pass[i] - f_scalar[i]).norm());
    std::printf("[ measured ] largest force %.3e N, largest difference %.3e N (bound %.1e)\n",
                largest(f_scalar), worst, bound);
    EXPECT_LE(worst, bound);
    EXPECT_NEAR(e_pass, e_scalar, 1e-12 * e_scalar);
    for (int k = 0; k < int(m.nodes.size()); ++k) {
      if (is_centred(m, k, model.rest_position))
        EXPECT_EQ(q_pass[size_t(k)].coeffs(), d.rotations[size_t(k)].coeffs()) << "node " << k;
      else
        EXPECT_LE((q_pass[size_t(k)].coeffs() - q_scalar[size_t(k)].coeffs()).norm(), 1e-12)
            << "node " << k;
    }
  }
}

TEST(ShapeMemoryCentred, ZeroForceUnderARigidMotion) {
  const Model model = regular_block();
  const ShapeMemory& m = model.shape_memory[0];
  std::mt19937 rng(19);
  const Eigen::Matrix3d R = testing::random_rotation(rng);
  std::vector<Vec3> x;
  for (const Vec3& X : model.rest_position) x.push_back(R * X + Vec3(0.1, -0.2, 0.05));
  std::vector<Eigen::Quaterniond> q(m.nodes.size(), Eigen::Quaterniond(R));
  std::vector<Vec3> f(x.size(), Vec3::Zero());
  std::vector<double> blocks = testing::block_scratch(m.plan);
  const double energy = add_shape_memory_forces(m, model.rest_position, x, q, f, blocks);
  EXPECT_LT(largest(f), 1e-13);  // K = 50 N/m on 5 mm cells: round-off is ~1e-16 N
  EXPECT_LT(energy, 1e-28);
}

// A structured grid's centred nodes all find their neighbours at the same id offsets: their
// runs go as a stencil over the coordinate arrays, with the node-by-node pass's forces up to
// the order of their sums.
TEST(ShapeMemoryCentred, StencilRunsGiveTheNodeByNodeForces) {
  Model model = regular_block();
  const ShapeMemory& m = model.shape_memory[0];
  ASSERT_TRUE(m.centred_on_stencil);
  const std::array<int, 6> expected{-49, -7, -1, 1, 7, 49};  // 7 x 7 x 7 nodes, x fastest
  EXPECT_EQ(m.centred_stencil, expected);
  std::mt19937 rng(23);
  const Deformed d = deformed(model, rng);
  std::vector<Vec3> f_stencil(d.x.size(), Vec3::Zero()), f_nodes = f_stencil;
  std::vector<Eigen::Quaterniond> q_stencil = d.rotations, q_nodes = d.rotations;
  std::vector<double> blocks = testing::block_scratch(m.plan);
  const double e_stencil =
      add_shape_memory_forces(m, model.rest_position, d.x, q_stencil, f_stencil, blocks);
  model.shape_memory[0].centred_on_stencil = false;
  const double e_nodes =
      add_shape_memory_forces(m, model.rest_position, d.x, q_nodes, f_nodes, blocks);
  const double scale = largest(f_nodes);
  double worst = 0.0;
  for (size_t i = 0; i < d.x.size(); ++i)
    worst = std::max(worst, (f_stencil[i] - f_nodes[i]).norm());
  EXPECT_LE(worst, 1e-14 * scale);
  EXPECT_NEAR(e_stencil, e_nodes, 1e-14 * e_nodes);
  // An irregular grid's nodes are not centred; an icosphere's rings, none either: no stencil.
  EXPECT_FALSE(block().shape_memory[0].centred_on_stencil);
}

}  // namespace
}  // namespace phymul
