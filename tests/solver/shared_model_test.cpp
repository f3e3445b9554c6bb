// One compiled Model drives several Data at once: a step reads the model and writes only its
// own data, so four runs on four threads give the bits of the same four runs one after the
// other.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <thread>
#include <vector>

#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "support/models.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

bool same_bits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

// Run k: the study's coarse 50 mL scene (shape memory, joint bladder and prostate volumes,
// stitches, the rigid probe), its nodes started with velocities of seed k.
Data run(const Model& model, unsigned k, int steps) {
  Data data = make_data(model);
  std::mt19937 rng(k);
  std::normal_distribution<double> speed(0.0, 1e-3);  // m/s
  for (int i = 0; i < model.node_count(); ++i)
    if (model.inverse_mass[i] != Vec3::Zero())
      data.v[i] = testing::random_vec3(speed, rng)
                      .cwiseProduct((model.inverse_mass[i].array() > 0.0).cast<double>().matrix());
  for (int s = 0; s < steps; ++s) step(model, data);
  return data;
}

TEST(SharedModel, FourDataOnFourThreadsMatchFourRunsInTurnBitForBit) {
  const Model model = compile_scene(
      load_scene(testing::source_dir() / "examples" / "prostate" / "coarse" / "50mL_rigid.yaml"));
  constexpr int kRuns = 4, kSteps = 1500;  // 0.4 s: the probe rises into the prostate from 0.2 s
  std::vector<Data> in_turn;
  for (unsigned k = 0; k < kRuns; ++k) in_turn.push_back(run(model, k, kSteps));
  std::vector<Data> together(kRuns);
  std::vector<std::thread> threads;
  for (unsigned k = 0; k < kRuns; ++k)
    threads.emplace_back([&, k] { together[k] = run(model, k, kSteps); });
  for (std::thread& t : threads) t.join();
  for (int k = 0; k < kRuns; ++k) {
    EXPECT_TRUE(same_bits(in_turn[k].x, together[k].x)) << "run " << k << ": positions";
    EXPECT_TRUE(same_bits(in_turn[k].v, together[k].v)) << "run " << k << ": velocities";
    EXPECT_TRUE(same_bits(in_turn[k].f, together[k].f)) << "run " << k << ": forces";
    EXPECT_EQ(in_turn[k].contact_force[0], together[k].contact_force[0]) << "run " << k;
  }
  // The runs differ from each other: the test compares four different histories.
  EXPECT_FALSE(same_bits(in_turn[0].x, in_turn[1].x));
  EXPECT_GT(in_turn[0].contact_force[0].norm(), 0.0);  // the probe is pushing
}

}  // namespace
}  // namespace phymul
