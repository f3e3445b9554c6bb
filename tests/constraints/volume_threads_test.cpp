// The volume projections' per-node loops and sums run in parallel on large surfaces, in fixed
// chunks: the thread count must not change a single bit of the result.
#include <gtest/gtest.h>
#include <omp.h>

#include <cstring>
#include <random>

#include "constraints/constraints.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

bool same_bits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

TEST(VolumeThreads, ProjectionsGiveBitIdenticalResultsOnOneAndTwoThreads) {
  // A 24^3 block: 3,458 surface nodes and 6,912 triangles, above the parallel threshold.
  Model model;
  const int c = add_elastic_component(
      model, "block", make_box(Vec3(0.08, 0.08, 0.08), {24, 24, 24}, CellType::hexa),
      testing::material(20.0));
  add_volume_constraint(model, c);
  finalize(model);
  ASSERT_GT(model.volumes[0].nodes.size(), 2048u);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-4e-4, 4e-4);
  std::vector<Vec3> x0 = model.rest_position, v0(x0.size());
  for (size_t i = 0; i < x0.size(); ++i) {
    x0[i] += testing::random_vec3(u, rng) + 0.05 * Vec3(0, 0, x0[i].z() * x0[i].x());
    v0[i] = testing::random_vec3(u, rng) * 100.0;
  }
  std::vector<std::vector<Vec3>> xs, vs;
  const int threads_before = omp_get_max_threads();
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    std::vector<Vec3> x = x0, v = v0, scratch(x0.size());
    Data data = allocate_data(model);
    project_volumes(model, data.controls, *data.work, x, 0.0, scratch);
    project_volume_velocities(model, *data.work, x, v, scratch);
    xs.push_back(x);
    vs.push_back(v);
  }
  omp_set_num_threads(threads_before);
  EXPECT_TRUE(same_bits(xs[0], xs[1]));
  EXPECT_TRUE(same_bits(vs[0], vs[1]));
  // And the projections did their work: the volume is the target, its rate zero.
  const VolumeConstraint& vc = model.volumes[0];
  std::vector<Vec3> grad(x0.size());
  volume_gradient(vc, xs[0], grad);
  double rate = 0.0, scale = 0.0;
  for (int i : vc.nodes) rate += grad[i].dot(vs[0][i]), scale += grad[i].norm() * vs[0][i].norm();
  EXPECT_LT(std::abs(rate), 1e-12 * scale);
  EXPECT_FALSE(same_bits(xs[0], x0));
}

}  // namespace
}  // namespace phymul
