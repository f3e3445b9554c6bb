// The joint projection of volume constraints sharing nodes (coupled_volume.hpp): all the
// multipliers solved together, against Gauss-Seidel sweeps of the single-surface projection.
#include <gtest/gtest.h>

#include <random>

#include "constraints/constraints.hpp"
#include "constraints/coupled_volume.hpp"
#include "constraints/volume_lanes.hpp"
#include "phymul/simulation.hpp"
#include "support/kernels.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

// Two 1 x 8 x 8 cm slabs sharing their 8 x 8 cm wall, their outer faces held: what is free of
// either surface is mostly the shared wall, where the two gradients are opposite. Projecting
// one chamber undoes most of the other's projection, the worst case for Gauss-Seidel.
Model two_slabs() {
  const Mesh mesh = make_box(Vec3(0.02, 0.08, 0.08), {4, 8, 8}, CellType::hexa);
  Model model;
  add_elastic_component(model, "slabs", mesh, testing::material(20.0));
  model.volumes.push_back(
      testing::surface_of_cells(mesh, "left", [](const Vec3& p) { return p.x() < 0.0; }));
  model.volumes.push_back(
      testing::surface_of_cells(mesh, "right", [](const Vec3& p) { return p.x() >= 0.0; }));
  std::vector<int> outer;
  for (int i = 0; i < model.node_count(); ++i)
    if (std::abs(std::abs(mesh.points[i].x()) - 0.01) < 1e-9) outer.push_back(i);
  add_fixed_nodes(model, outer);
  finalize(model);
  return model;
}

// Every free node moved by up to 1 mm at random: both volumes off by about 1e-3 relative.
std::vector<Vec3> shaken(const Model& m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  std::vector<Vec3> x = m.rest_position;
  for (int i = 0; i < m.node_count(); ++i)
    if (m.inverse_mass[i].squaredNorm() > 0.0) x[i] += testing::random_vec3(u, rng);
  return x;
}

double worst_relative_error(const Model& m, const std::vector<Vec3>& x) {
  double worst = 0.0;
  for (const VolumeConstraint& c : m.volumes)
    worst = std::max(worst,
                     std::abs(enclosed_volume(x, c.triangles) - c.target_volume) / c.target_volume);
  return worst;
}

TEST(JointVolumes, OneProjectionHoldsEveryVolumeWhereGaussSeidelNeedsManySweeps) {
  const Model m = two_slabs();
  ASSERT_TRUE(m.coupled_volumes);
  std::vector<Vec3> scratch(size_t(m.node_count()));
  for (unsigned seed : {1u, 2u, 3u}) {
    const std::vector<Vec3> start = shaken(m, seed);
    EXPECT_GT(worst_relative_error(m, start), 1e-4);
    // Reference: sweeps of the exact single-surface projection until both hold to 1e-12.
    std::vector<Vec3> swept = start;
    int sweeps = 0;
    while (worst_relative_error(m, swept) > 1e-12 && sweeps < 10000) {
      for (const VolumeConstraint& c : m.volumes) project_volume(c, m.inverse_mass, swept, scratch);
      ++sweeps;
    }
    std::vector<Vec3> joint = start;
    Data data = allocate_data(m);
    project_volumes(m, data.controls, *data.work, joint, 0.0, scratch);
    double moved = 0.0, apart = 0.0;
    for (int i = 0; i < m.node_count(); ++i) {
      moved = std::max(moved, (joint[i] - start[i]).norm());
      apart = std::max(apart, (joint[i] - swept[i]).norm());
    }
    std::printf(
        "seed %u: Gauss-Seidel %d sweeps; joint error %.3g, moved %.3g m, %.3g m from "
        "the sweeps' result\n",
        seed, sweeps, worst_relative_error(m, joint), moved, apart);
    EXPECT_GT(sweeps, 20);
    EXPECT_LT(worst_relative_error(m, joint), 1e-12);
    // Both are projections along the same gradients to the same volumes: they differ by
    // second order in the move only.
    EXPECT_LT(apart, 0.1 * moved);
  }
}

TEST(JointVolumes, OneStepHoldsEveryVolume) {
  Model m = two_slabs();
  m.gravity = Vec3(0, 0, -9.81);
  m.damping = 5.0;
  Simulator sim(m);
  sim.data().x = shaken(m, 7);  // far off both targets: the step's projection puts them back
  sim.step();
  const double error = worst_relative_error(m, sim.data().x);
  std::printf("after one step: worst relative volume error %.3g\n", error);
  EXPECT_LT(error, 1e-12);
}

TEST(JointVolumes, TheChordLandsWithTheGradientsTheVelocityProjectionReuses) {
  // Whatever the start error (a contact leaves 1e-5 to 1e-4 in the prostate study), the chord
  // step that lands takes the gradients at the projected positions: the velocity projection
  // that follows finds them kept there and needs no gradient pass of its own.
  const Model m = two_slabs();
  std::vector<Vec3> grad(size_t(m.node_count()));
  const std::vector<Vec3> far = shaken(m, 11);
  for (double scale : {1.0, 0.1, 0.03, 1e-2, 1e-3, 1e-5}) {
    std::vector<Vec3> x(far.size());
    for (size_t i = 0; i < x.size(); ++i)
      x[i] = m.rest_position[i] + scale * (far[i] - m.rest_position[i]);
    const double start = worst_relative_error(m, x);
    Data data = allocate_data(m);
    Workspace& work = *data.work;
    ASSERT_TRUE(project_coupled_volumes(m, data.controls, work, x, 0.0, grad));
    bool kept = work.joint.factor_valid;  // what the velocity projection asks before reusing
    for (size_t k = 0; k < m.volumes.size(); ++k)
      kept = kept && gradient_kept_at(m.volumes[k], work.volumes[k], x);
    std::printf("start error %.3g: after %.3g, gradients kept at the result: %s\n", start,
                worst_relative_error(m, x), kept ? "yes" : "no");
    EXPECT_LT(worst_relative_error(m, x), 1e-12);
    EXPECT_TRUE(kept) << "start error " << start;
  }
}

TEST(JointVolumes, VelocityProjectionLeavesNoVolumeRateAndMatchesTheSweepsLimit) {
  const Model m = two_slabs();
  const std::vector<Vec3> x = shaken(m, 4);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  std::vector<Vec3> v(size_t(m.node_count()));
  for (int i = 0; i < m.node_count(); ++i)
    v[i] = testing::random_vec3(u, rng).cwiseProduct(
        (m.inverse_mass[i].array() > 0.0).cast<double>().matrix());
  std::vector<Vec3> grad(v.size()), joint = v;
  Data data = allocate_data(m);
  ASSERT_TRUE(project_coupled_volume_velocities(m, *data.work, x, joint, grad));
  // Independent reference: the single-constraint rate removal swept to its limit (linear
  // Gauss-Seidel on G W G^T mu = G v converges to the same solution).
  std::vector<Vec3> swept = v;
  for (int sweep = 0; sweep < 20000; ++sweep)
    for (const VolumeConstraint& c : m.volumes) {
      volume_gradient(c, x, grad);
      double rate = 0.0, weight = 0.0;
      for (int i : c.nodes) {
        rate += grad[i].dot(swept[i]);
        weight += grad[i].dot(grad[i].cwiseProduct(m.inverse_mass[i]));
      }
      for (int i : c.nodes) swept[i] -= rate / weight * grad[i].cwiseProduct(m.inverse_mass[i]);
    }
  double difference = 0.0, speed = 0.0;
  for (size_t i = 0; i < v.size(); ++i) {
    difference = std::max(difference, (joint[i] - swept[i]).norm());
    speed = std::max(speed, v[i].norm());
  }
  for (const VolumeConstraint& c : m.volumes) {
    volume_gradient(c, x, grad);
    double before = 0.0, after = 0.0, scale = 0.0;
    for (int i : c.nodes) {
      before += grad[i].dot(v[i]);
      after += grad[i].dot(joint[i]);
      scale += grad[i].norm() * joint[i].norm();
    }
    std::printf("%s: dV/dt %.3g m^3/s before, %.3g after (scale %.3g)\n", c.component.c_str(),
                before, after, scale);
    EXPECT_GT(std::abs(before), 1e-3 * scale);
    EXPECT_LT(std::abs(after), 1e-13 * scale);
  }
  std::printf("joint against swept velocities: %.3g m/s (speeds up to %.3g m/s)\n", difference,
              speed);
  EXPECT_LT(difference, 1e-9 * speed);
}

TEST(JointVolumes, PressuresRemovedFromAResidualLeaveItOrthogonalToEveryFreeGradient) {
  // Static relaxation's residual: what the two pressures balance together taken out, nothing
  // of either free gradient may be left, whether removed along the free or whole gradients.
  const Model m = two_slabs();
  const std::vector<Vec3> x = shaken(m, 8);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3> r0(size_t(m.node_count())), grad(r0.size());
  for (Vec3& f : r0) f = testing::random_vec3(u, rng);
  for (bool on_free_axes : {true, false}) {
    std::vector<Vec3> r = r0;
    Data data = allocate_data(m);
    ASSERT_TRUE(remove_coupled_volume_pressures(m, *data.work, x, r, grad, on_free_axes));
    for (const VolumeConstraint& c : m.volumes) {
      volume_gradient(c, x, grad);
      double before = 0.0, after = 0.0, scale = 0.0;
      for (int i : c.nodes) {
        const Vec3 free_part =
            grad[i].cwiseProduct((m.inverse_mass[i].array() > 0.0).cast<double>().matrix());
        before += free_part.dot(r0[i]);
        after += free_part.dot(r[i]);
        scale += free_part.norm() * r0[i].norm();
      }
      std::printf("%s (%s): F.r %.3g before, %.3g after (scale %.3g)\n", c.component.c_str(),
                  on_free_axes ? "free" : "whole", before, after, scale);
      EXPECT_GT(std::abs(before), 1e-3 * scale);
      EXPECT_LT(std::abs(after), 1e-12 * scale);
    }
    double held_changed = 0.0;  // removed along free parts: held axes keep their residual
    for (size_t i = 0; i < r.size(); ++i)
      if (m.inverse_mass[i].squaredNorm() == 0.0)
        held_changed = std::max(held_changed, (r[i] - r0[i]).norm());
    if (on_free_axes)
      EXPECT_EQ(held_changed, 0.0);
    else
      EXPECT_GT(held_changed, 0.0);  // the supports carry part of the pressures
  }
}

}  // namespace
}  // namespace phymul
