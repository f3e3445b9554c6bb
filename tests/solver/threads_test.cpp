// The force passes (shape memory, explicit finite elements) run blocks of one colour in
// parallel; every sum keeps one order, so the thread count must not change a single bit of
// the result.
#include <gtest/gtest.h>
#include <omp.h>

#include <cstring>

#include "forces/shape_memory.hpp"
#include "model/parallel_plan.hpp"
#include "phymul/simulation.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

// A 16^3 hexahedral block (4913 nodes: above the parallel threshold), volume kept, base
// fixed, sagging under gravity: surface and interior memories, all constraints busy.
Model sagging_block(FrameMode frame) {
  Model model;
  const int c = add_elastic_component(
      model, "block", make_box(Vec3(0.08, 0.08, 0.08), {16, 16, 16}, CellType::hexa),
      testing::material(20.0, frame));
  add_volume_constraint(model, c);
  add_fixed_nodes(model, model.components[c].node_sets.at("bottom"));
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 5.0;
  finalize(model);
  return model;
}

Data run_with_threads(const Model& model, int threads, int steps) {
  const int previous = omp_get_max_threads();
  omp_set_num_threads(threads);
  Simulator sim(model);
  for (int k = 0; k < steps; ++k) sim.step();
  omp_set_num_threads(previous);
  return sim.data();
}

bool bitwise_equal(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

// Runs 60 steps on one thread, then on two and three: every state bit for bit the same.
// Returns the one-thread state.
Data expect_thread_count_invariant(const Model& model) {
  const Data one = run_with_threads(model, 1, 60);
  for (int threads : {2, 3}) {
    const Data many = run_with_threads(model, threads, 60);
    EXPECT_TRUE(bitwise_equal(one.x, many.x)) << threads << " threads";
    EXPECT_TRUE(bitwise_equal(one.v, many.v)) << threads << " threads";
    EXPECT_TRUE(bitwise_equal(one.f, many.f)) << threads << " threads";
    EXPECT_EQ(std::memcmp(&one.shape_memory_energy, &many.shape_memory_energy, sizeof(double)), 0);
  }
  return one;
}

class Threads : public ::testing::TestWithParam<FrameMode> {};

TEST_P(Threads, OneTwoAndThreeThreadsGiveBitIdenticalStates) {
  const Model model = sagging_block(GetParam());
  const Data one = expect_thread_count_invariant(model);
  // It moved: the comparison is not between two resting blocks.
  EXPECT_GT((one.x.back() - model.rest_position.back()).norm(), 1e-4);
}

INSTANTIATE_TEST_SUITE_P(ShapeMemory, Threads,
                         ::testing::Values(FrameMode::polar, FrameMode::frame));

// The explicit finite elements (TLED) run their cells in the same coloured blocks: a 16^3
// block (4096 cells, above the parallel threshold) sagging under gravity, base fixed.
TEST(ThreadsTled, OneTwoAndThreeThreadsGiveBitIdenticalStates) {
  Model model;
  MaterialSpec fem;
  fem.model = ElasticModel::fem;
  fem.young = 20e3;
  fem.poisson = 0.45;
  fem.density = 1000.0;
  const int c = add_elastic_component(
      model, "block", make_box(Vec3(0.08, 0.08, 0.08), {16, 16, 16}, CellType::hexa), fem);
  add_fixed_nodes(model, model.components[c].node_sets.at("bottom"));
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 5.0;
  finalize(model);
  ASSERT_EQ(model.explicit_fem.size(), 1u);
  const Data one = expect_thread_count_invariant(model);
  EXPECT_GT((one.x.back() - model.rest_position.back()).norm(), 1e-6);
}

// Blocks of one colour never write the same node: the plan is what makes the parallel pass
// race-free, so check it directly on a mesh whose numbering is not a grid's.
TEST(ParallelPlan, BlocksOfOneColourWriteDisjointNodes) {
  for (const Mesh& mesh : {make_box(Vec3(0.08, 0.08, 0.08), {16, 16, 16}, CellType::hexa),
                           make_box(Vec3(0.05, 0.03, 0.04), {12, 9, 10}, CellType::tetra),
                           make_ellipsoid_volume(Vec3(0.03, 0.02, 0.02), 3, 4)}) {
    Model model;
    add_elastic_component(model, "body", mesh, testing::material(10.0));
    const ShapeMemory& m = model.shape_memory[0];
    const ParallelPlan& plan = m.plan;
    ASSERT_GT(plan.blocks(), 1);
    EXPECT_EQ(plan.block_start.back(), int(m.nodes.size()));
    std::vector<int> writer(size_t(model.node_count()), -1);
    for (size_t c = 0; c + 1 < plan.colour_start.size(); ++c) {
      std::fill(writer.begin(), writer.end(), -1);
      for (int index = plan.colour_start[c]; index < plan.colour_start[c + 1]; ++index) {
        const int b = plan.colour_blocks[index];
        for (int k = plan.block_start[b]; k < plan.block_start[b + 1]; ++k) {
          auto claim = [&](int i) {
            EXPECT_TRUE(writer[i] == -1 || writer[i] == b)
                << "node " << i << " written by blocks " << writer[i] << " and " << b;
            writer[i] = b;
          };
          claim(m.nodes[k]);
          for (int j : m.neighbours.row(k)) claim(j);
        }
      }
    }
    // Every block has exactly one colour.
    std::vector<int> seen(plan.block_start.size() - 1, 0);
    for (int b : plan.colour_blocks) ++seen[b];
    for (int count : seen) EXPECT_EQ(count, 1);
  }
}

}  // namespace
}  // namespace phymul
