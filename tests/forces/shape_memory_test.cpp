#include "forces/shape_memory.hpp"

#include <gtest/gtest.h>

#include <random>

#include "phymul/forces.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

using testing::material;

struct Case {
  const char* name;
  Mesh mesh;
  MaterialSpec material;
};

std::vector<Case> cases(FrameMode frame) {
  const Vec3 size(0.03, 0.02, 0.025);
  return {
      {"hexa box", make_box(size, {3, 2, 4}, CellType::hexa), material(50.0, frame)},
      {"tetra box", make_box(size, {2, 3, 2}, CellType::tetra), material(50.0, frame)},
      {"ellipsoid volume", make_ellipsoid_volume({0.02, 0.015, 0.01}, 1, 2), material(50.0, frame)},
      {"ellipsoid surface", make_ellipsoid_surface({0.02, 0.015, 0.01}, 2),
       testing::surface_material(50.0, 0.1, frame)},
  };
}

double largest_force(const Data& s) {
  double m = 0.0;
  for (const Vec3& f : s.f) m = std::max(m, f.norm());
  return m;
}

class ShapeMemoryFrames : public ::testing::TestWithParam<FrameMode> {};

TEST_P(ShapeMemoryFrames, ZeroAtRest) {
  for (Case& c : cases(GetParam())) {
    const Model model = testing::single_component(c.mesh, c.material);
    Data s = allocate_data(model);
    compute_forces(model, s, 0.0);
    // K = 50 N/m on cm-sized meshes: round-off forces are ~1e-16 N.
    EXPECT_LT(largest_force(s), 1e-13) << c.name;
  }
}

TEST_P(ShapeMemoryFrames, ZeroUnderRandomRigidMotions) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> shift(-0.5, 0.5);
  for (Case& c : cases(GetParam())) {
    const Model model = testing::single_component(c.mesh, c.material);
    Data s = allocate_data(model);
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::Matrix3d R = testing::random_rotation(rng);
      const Vec3 t = testing::random_vec3(shift, rng);
      for (int i = 0; i < model.node_count(); ++i) s.x[i] = R * model.rest_position[i] + t;
      compute_forces(model, s, 0.0);
      // A force of 1 mm of stretch would be 0.05 N: rigid motion leaves only round-off.
      EXPECT_LT(largest_force(s), 1e-11) << c.name << " trial " << trial;
    }
  }
}

TEST_P(ShapeMemoryFrames, PullsADisplacedNodeBack) {
  // Interior node of a 4x4x4 grid: its neighbours stay, so its attraction position is its
  // rest position and the force is exactly -K * displacement on it.
  const double K = 80.0;
  const Mesh mesh = make_box(Vec3(0.04, 0.04, 0.04), {4, 4, 4}, CellType::hexa);
  MaterialSpec m = material(K, GetParam(), /*reaction=*/false);
  const Model model = testing::single_component(mesh, m);
  int centre = 0;
  for (int i = 0; i < model.node_count(); ++i)
    if (model.rest_position[i].norm() < 1e-9) centre = i;
  Data s = allocate_data(model);
  const Vec3 delta(0.001, -0.002, 0.0015);
  s.x[centre] += delta;
  compute_forces(model, s, 0.0);
  EXPECT_LT((s.f[centre] + K * delta).norm(), 1e-12 * K);
}

INSTANTIATE_TEST_SUITE_P(BothModes, ShapeMemoryFrames,
                         ::testing::Values(FrameMode::polar, FrameMode::frame),
                         [](const auto& info) {
                           return info.param == FrameMode::polar ? "polar" : "frame";
                         });

TEST(ShapeMemory, ReactionKeepsMomentum) {
  // With the reaction option the internal forces sum to zero for any deformation.
  std::mt19937 rng(3);
  std::normal_distribution<double> jitter(0.0, 0.002);
  const Mesh mesh = make_box(Vec3(0.03, 0.03, 0.03), {3, 3, 3}, CellType::hexa);
  for (bool reaction : {true, false}) {
    const Model model = testing::single_component(mesh, material(40.0, FrameMode::polar, reaction));
    Data s = allocate_data(model);
    for (Vec3& x : s.x) x += testing::random_vec3(jitter, rng);
    compute_forces(model, s, 0.0);
    Vec3 total = Vec3::Zero();
    double scale = 0.0;
    for (const Vec3& f : s.f) total += f, scale += f.norm();
    if (reaction)
      EXPECT_LT(total.norm(), 1e-14 * scale);
    else  // the published form does not balance: the option is what buys the conservation
      EXPECT_GT(total.norm(), 1e-6 * scale);
  }
}

TEST(ShapeMemory, RotationExtractionMatchesKnownRotation) {
  std::mt19937 rng(11);
  Eigen::Matrix3d S;
  S << 3, 0.2, 0.1, 0.2, 2, 0.3, 0.1, 0.3, 1;  // symmetric positive definite stretch
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Matrix3d R = testing::random_rotation(rng);
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    extract_rotation(R * S, q, 100);
    EXPECT_LT((q.toRotationMatrix() - R).norm(), 1e-12) << trial;
  }
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// With the reaction option in polar mode the forces are exactly -dE/dx of the shape-memory
// energy E = sum K |a - x|^2 / 2, rotation derivative and normal pair included.
TEST(ShapeMemory, PolarReactionForcesAreTheEnergyGradient) {
  std::mt19937 rng(2);
  std::normal_distribution<double> jitter(0.0, 2e-3);
  for (Case& c : cases(FrameMode::polar)) {
    const Model model = testing::single_component(c.mesh, c.material);
    Data s = allocate_data(model);
    for (Vec3& x : s.x) x += testing::random_vec3(jitter, rng);
    compute_forces(model, s, 0.0);
    auto energy = [&](const std::vector<Vec3>& x) {
      Data probe = s;
      probe.x = x;
      compute_forces(model, probe, 0.0);
      return probe.shape_memory_energy;
    };
    double worst = 0.0, largest = 0.0;
    const double h = 1e-7;
    for (int i = 0; i < model.node_count(); i += 3)
      for (int a = 0; a < 3; ++a) {
        std::vector<Vec3> p = s.x, q = s.x;
        p[i][a] += h;
        q[i][a] -= h;
        const double gradient = (energy(p) - energy(q)) / (2.0 * h);
        worst = std::max(worst, std::abs(s.f[i][a] + gradient));
        largest = std::max(largest, std::abs(gradient));
      }
    // Central differences of step 1e-7 m are good to about 1e-9 of the force here.
    EXPECT_LT(worst, 1e-8 * largest) << c.name << " largest force " << largest;
  }
}

}  // namespace
}  // namespace phymul
