// The single-precision polar pass (forces/shape_memory_single.cpp) against the double one: its
// accuracy cost, bounded from float's unit round-off u = 2^-24 and the scale of the forces.
//
// Error model: a node's force is its own pull plus the reactions of its n neighbours' memories
// on it. Each is K times a length of at most h (the longest neighbour offset) computed in float:
// the offsets are rounded once (u h), the fit and the settled rotation add a few u more (the
// Newton turns stop below 1e-4 rad, the next turn, of its square, is under u; the rotation
// Hessians of these meshes are well conditioned), so each term is within 4 u K h, and a node's
// force within (n + 1) 4 u K h. The energy K |pull|^2 / 2 of a node then moves by at most
// K |pull| 4 u h (first order).
#include "forces/shape_memory_single.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <cstdio>
#include <limits>
#include <random>

#include "forces/shape_memory.hpp"
#include "forces/shape_memory_batch.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

constexpr int W = kShapeMemorySingleLanes;
constexpr double u = std::numeric_limits<float>::epsilon() / 2.0;  // 2^-24

// A 3 cm block of 10^3 hexahedra, K = 50 N/m (3 mm cells), jittered: no node centred, every
// one in the lanes.
Model grid() {
  return testing::single_component(
      testing::jittered(make_box(Vec3(0.03, 0.03, 0.03), {10, 10, 10}, CellType::hexa), 0.003),
      testing::material(50.0));
}

// An icosphere of radius 2 cm (3 subdivisions, 642 nodes), K = 50 N/m: rings of 5 and 6 with
// their normal pair.
Model icosphere() {
  return testing::single_component(make_ellipsoid_surface({0.02, 0.02, 0.02}, 3),
                                   testing::surface_material(50.0, 0.1, FrameMode::polar));
}

// The body rotated at random, bent, sheared and shaken (noise in m), moved by t; every memory's
// rotation one step old (converged, then turned by 5 mrad), as a dynamic step finds them.
struct Deformed {
  std::vector<Vec3> x;
  std::vector<Eigen::Quaterniond> rotations;
};

Deformed deformed(const Model& model, std::mt19937& rng, double noise, const Vec3& t) {
  const ShapeMemory& m = model.shape_memory[0];
  const Eigen::Matrix3d R = testing::random_rotation(rng);
  std::uniform_real_distribution<double> shake(-noise, noise);
  Deformed d;
  for (const Vec3& X : model.rest_position) {
    const Vec3 bent(X.x() + 4.0 * X.z() * X.z(), X.y() * (1.0 + 5.0 * X.x()), 0.9 * X.z());
    d.x.push_back(R * bent + Vec3(shake(rng), shake(rng), shake(rng)) + t);
  }
  for (int k = 0; k < int(m.nodes.size()); ++k) {
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    attraction_position(m, k, model.rest_position, d.x, q);
    d.rotations.push_back(q * testing::small_turn(rng, 0.005));
  }
  return d;
}

// The longest neighbour offset, now or at rest (m), and the most neighbours of a memory.
double longest_offset(const ShapeMemory& m, std::span<const Vec3> rest, std::span<const Vec3> x) {
  double h = 0.0;
  for (int k = 0; k < int(m.nodes.size()); ++k)
    for (int j : m.neighbours.row(k))
      h = std::max({h, (x[j] - x[m.nodes[k]]).norm(), (rest[j] - rest[m.nodes[k]]).norm()});
  return h;
}
int most_neighbours(const ShapeMemory& m) {
  int n = 0;
  for (int k = 0; k < int(m.nodes.size()); ++k) n = std::max(n, int(m.neighbours.row(k).size()));
  return n;
}

double largest(std::span<const Vec3> f) {
  double m = 0.0;
  for (const Vec3& v : f) m = std::max(m, v.norm());
  return m;
}

// Both passes from the same state: forces within (n + 1) 4 u K h node by node, the energy
// within 4 u K h sum |pull|, the rotations within 1e-6 rad; most lanes in float.
void expect_single_close_to_double(const Model& model, std::mt19937& rng, double noise,
                                   const Vec3& t) {
  const ShapeMemory& m = model.shape_memory[0];
  const Deformed d = deformed(model, rng, noise, t);
  std::vector<Vec3> f_double(d.x.size(), Vec3::Zero()), f_single = f_double;
  std::vector<Eigen::Quaterniond> q_double = d.rotations, q_single = d.rotations;
  const double e_double = add_shape_memory_forces(m, model.rest_position, d.x, q_double, f_double);
  const double e_single =
      add_shape_memory_forces_single(m, model.rest_position, d.x, q_single, f_single);

  const double h = longest_offset(m, model.rest_position, d.x);
  const double term = 4.0 * u * m.stiffness * h;  // N, one pull or reaction
  const double bound = (most_neighbours(m) + 1) * term;
  double error = 0.0, pulls = 0.0;
  for (size_t i = 0; i < d.x.size(); ++i)
    error = std::max(error, (f_single[i] - f_double[i]).norm());
  for (int k = 0; k < int(m.nodes.size()); ++k) {
    Eigen::Quaterniond q = q_double[size_t(k)];
    pulls += (attraction_position(m, k, model.rest_position, d.x, q) - d.x[m.nodes[k]]).norm();
  }
  const double scale = largest(f_double);
  ASSERT_GT(scale, 100.0 * bound);  // a real deformation
  EXPECT_LE(error, bound);
  EXPECT_NEAR(e_single, e_double, term * pulls);
  double turn = 0.0;
  for (size_t k = 0; k < q_double.size(); ++k)
    turn = std::max(turn, q_single[k].angularDistance(q_double[k]));
  EXPECT_LT(turn, 1e-6);
  std::printf(
      "[ measured ] %zu nodes, |f|max %.3e N: max error %.3e N = %.2f u K h (bound %.0f), "
      "relative %.2e; energy relative %.2e; rotations within %.1e rad\n",
      m.nodes.size(), scale, error, error / (u * m.stiffness * h), bound / (u * m.stiffness * h),
      error / scale, std::abs(e_single - e_double) / e_double, turn);

  int in_lanes = 0, lanes = 0;
  std::vector<Vec3> f(d.x.size(), Vec3::Zero());
  std::vector<Eigen::Quaterniond> q = d.rotations;
  for (int b = 0; b < m.plan.blocks(); ++b)
    for (int p = m.plan.block_start[b]; p < m.batched_end[b]; p += W) {
      const int used = std::min(W, m.batched_end[b] - p);
      std::array<bool, W> batched;
      add_polar_batch_forces_single(m, m.batch_order.data() + p, used, model.rest_position, d.x, q,
                                    f, &batched);
      for (int l = 0; l < used; ++l) in_lanes += batched[size_t(l)], ++lanes;
    }
  EXPECT_GE(in_lanes, lanes - lanes / 50);  // the double fallback stays rare
  EXPECT_GT(lanes, int(m.nodes.size()) * 4 / 5);
}

TEST(ShapeMemorySingle, ForcesOfADeformedRotatedGridMatchTheDoublePass) {
  const Model model = grid();
  std::mt19937 rng(3);
  for (double noise : {1e-5, 3e-4})  // m, on 3 mm cells
    expect_single_close_to_double(model, rng, noise, Vec3(0.01, -0.02, 0.005));
}

TEST(ShapeMemorySingle, ForcesOfADeformedIcosphereMatchTheDoublePass) {
  const Model model = icosphere();
  std::mt19937 rng(5);
  for (double noise : {1e-5, 3e-4}) expect_single_close_to_double(model, rng, noise, Vec3::Zero());
}

// 1 km from the origin, float would round absolute positions to 61 um, the bound's 40000
// times: the lanes only ever see offsets taken in double.
TEST(ShapeMemorySingle, AccurateFarFromTheOrigin) {
  const Model model = grid();
  std::mt19937 rng(7);
  expect_single_close_to_double(model, rng, 3e-4, Vec3(1000.0, -700.0, 400.0));
}

// Under a rigid motion every pull is zero: the float pass leaves forces of round-off only,
// (n + 1) 4 u K h, and finds the rotation to float precision.
TEST(ShapeMemorySingle, ZeroForceUnderARigidRotation) {
  for (const Model& model : {grid(), icosphere()}) {
    const ShapeMemory& m = model.shape_memory[0];
    std::mt19937 rng(9);
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::Matrix3d R = testing::random_rotation(rng);
      const Vec3 t(500.0, -200.0, 50.0);
      std::vector<Vec3> x;
      for (const Vec3& X : model.rest_position) x.push_back(R * X + t);
      std::vector<Eigen::Quaterniond> q;
      for (size_t k = 0; k < m.nodes.size(); ++k)
        q.push_back(Eigen::Quaterniond(R) * testing::small_turn(rng, 1e-3));
      std::vector<Vec3> f(x.size(), Vec3::Zero());
      const double energy = add_shape_memory_forces_single(m, model.rest_position, x, q, f);
      const double h = longest_offset(m, model.rest_position, x);
      const double bound = (most_neighbours(m) + 1) * 4.0 * u * m.stiffness * h;
      EXPECT_LT(largest(f), bound);
      // Each pull below 4 u h: the energy below K (4 u h)^2 / 2 a node.
      EXPECT_LT(energy, double(m.nodes.size()) * 0.5 * m.stiffness * std::pow(4.0 * u * h, 2));
      double turn = 0.0;
      for (const Eigen::Quaterniond& qk : q)
        turn = std::max(turn, qk.angularDistance(Eigen::Quaterniond(R)));
      EXPECT_LT(turn, 1e-6);
      EXPECT_NEAR(q[0].norm(), 1.0, 1e-12);  // renormalised in double
      if (trial == 0)
        std::printf(
            "[ measured ] rigid: |f|max %.2e N = %.2f u K h (bound %.0f); rotations %.1e rad\n",
            largest(f), largest(f) / (u * m.stiffness * h), bound / (u * m.stiffness * h), turn);
    }
  }
}

// Lanes whose warm start is far from their fit (a quarter turn away: the Newton turn would
// exceed 0.1 rad) redo their node on the double scalar path: their rotations come out bit for
// bit as the double pass's.
TEST(ShapeMemorySingle, LanesThatDoNotSettleGoTheDoubleWay) {
  const Model model = grid();
  const ShapeMemory& m = model.shape_memory[0];
  std::mt19937 rng(11);
  Deformed d = deformed(model, rng, 3e-4, Vec3::Zero());
  std::vector<bool> cold(m.nodes.size(), false);
  for (size_t k = 0; k < m.nodes.size(); k += 3) {
    d.rotations[k] = d.rotations[k] * Eigen::Quaterniond(Eigen::AngleAxisd(1.5, Vec3::UnitZ()));
    cold[k] = true;
  }
  std::vector<Eigen::Quaterniond> q_double = d.rotations, q_single = d.rotations;
  std::vector<Vec3> f(d.x.size(), Vec3::Zero());
  for (int k = 0; k < int(m.nodes.size()); ++k)
    add_polar_node_forces(m, k, model.rest_position, d.x, q_double, f);
  int fell_back = 0, in_lanes = 0;
  for (int b = 0; b < m.plan.blocks(); ++b)
    for (int p = m.plan.block_start[b]; p < m.batched_end[b]; p += W) {
      const int used = std::min(W, m.batched_end[b] - p);
      std::array<bool, W> batched;
      add_polar_batch_forces_single(m, m.batch_order.data() + p, used, model.rest_position, d.x,
                                    q_single, f, &batched);
      for (int l = 0; l < used; ++l) {
        const size_t k = size_t(m.batch_order[size_t(p + l)]);
        if (cold[k]) {
          EXPECT_FALSE(batched[size_t(l)]) << "memory node " << k;
        }
        if (batched[size_t(l)]) {
          ++in_lanes;
          continue;
        }
        ++fell_back;
        EXPECT_EQ(q_single[k].coeffs(), q_double[k].coeffs()) << "memory node " << k;
      }
    }
  EXPECT_GT(fell_back, 300);
  EXPECT_GT(in_lanes, 700);
}

// A batch of fewer than eight lanes writes its own nodes only.
TEST(ShapeMemorySingle, PartialBatchWritesItsNodesOnly) {
  const Model model = grid();
  const ShapeMemory& m = model.shape_memory[0];
  std::mt19937 rng(13);
  const Deformed d = deformed(model, rng, 3e-4, Vec3::Zero());
  const int* ks = m.batch_order.data() + m.plan.block_start[0];
  ASSERT_GE(m.batched_end[0] - m.plan.block_start[0], 3);
  std::vector<Vec3> f_single(d.x.size(), Vec3::Zero()), f_double = f_single;
  std::vector<Eigen::Quaterniond> q_single = d.rotations, q_double = d.rotations;
  add_polar_batch_forces_single(m, ks, 3, model.rest_position, d.x, q_single, f_single);
  for (int l = 0; l < 3; ++l)
    add_polar_node_forces(m, ks[l], model.rest_position, d.x, q_double, f_double);
  const double bound = 4.0 * 4.0 * u * m.stiffness * longest_offset(m, model.rest_position, d.x);
  for (size_t i = 0; i < d.x.size(); ++i)
    EXPECT_LE((f_single[i] - f_double[i]).norm(), bound) << "node " << i;
  for (size_t k = 0; k < q_single.size(); ++k)
    if (k != size_t(ks[0]) && k != size_t(ks[1]) && k != size_t(ks[2])) {
      EXPECT_EQ(q_single[k].coeffs(), d.rotations[k].coeffs()) << "memory node " << k;
    }
}

// Blocks of one colour run in parallel, every sum in one order: one thread or two, the same
// bits (a 16^3 block, above the parallel threshold).
TEST(ShapeMemorySingle, ThreadCountChangesNoBit) {
  const Model model = testing::single_component(
      make_box(Vec3(0.08, 0.08, 0.08), {15, 15, 15}, CellType::hexa), testing::material(20.0));
  const ShapeMemory& m = model.shape_memory[0];
  ASSERT_GE(m.nodes.size(), 4096u);
  std::mt19937 rng(15);
  const Deformed d = deformed(model, rng, 5e-4, Vec3::Zero());
  std::vector<Vec3> f[2];
  std::vector<Eigen::Quaterniond> q[2];
  double energy[2];
  const int previous = omp_get_max_threads();
  for (int threads = 1; threads <= 2; ++threads) {
    omp_set_num_threads(threads);
    f[threads - 1].assign(d.x.size(), Vec3::Zero());
    q[threads - 1] = d.rotations;
    energy[threads - 1] =
        add_shape_memory_forces_single(m, model.rest_position, d.x, q[threads - 1], f[threads - 1]);
  }
  omp_set_num_threads(previous);
  EXPECT_EQ(energy[0], energy[1]);
  for (size_t i = 0; i < d.x.size(); ++i) ASSERT_EQ(f[0][i], f[1][i]) << "node " << i;
  for (size_t k = 0; k < q[0].size(); ++k) ASSERT_EQ(q[0][k].coeffs(), q[1][k].coeffs());
}

}  // namespace
}  // namespace phymul
