// The volumes' projection with nodes held on a frictionless obstacle (coupled_volume.hpp):
// one solve, against the limit of alternating the contact's and the volumes' own stages.
#include <gtest/gtest.h>

#include <algorithm>

#include "constraints/constraints.hpp"
#include "constraints/contact.hpp"
#include "constraints/coupled_volume.hpp"
#include "phymul/simulation.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

using Shape = RigidObstacle::Shape;

// A 4 x 2 x 2 cm block of two chambers sharing their wall (x = 0), each keeping its volume:
// 0.1 mm above a floor, or (`probe`) hanging by its top face with a horizontal capsule along
// y (a probe) whose crown is 0.5 mm above the block's bottom.
Model chambers_on(bool probe) {
  const Mesh mesh = make_box(Vec3(0.04, 0.02, 0.02), {4, 2, 2}, CellType::hexa, Vec3(0, 0, 0.0101));
  Model model;
  const int c = add_elastic_component(model, "block", mesh, testing::material(300.0));
  model.volumes.push_back(
      testing::surface_of_cells(mesh, "left", [](const Vec3& p) { return p.x() < 0; }));
  model.volumes.push_back(
      testing::surface_of_cells(mesh, "right", [](const Vec3& p) { return p.x() > 0; }));
  if (probe) {
    add_fixed_nodes(model, model.components[size_t(c)].node_sets.at("top"));
    add_rigid_obstacle(model, testing::obstacle(Shape::capsule, Vec3(0, -0.05, -0.0144),
                                                Vec3::UnitY(), 0.015, 0.1));
  } else {
    add_rigid_obstacle(model, testing::obstacle(Shape::plane, Vec3::Zero(), Vec3::UnitZ()));
  }
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 2.0;
  finalize(model);
  return model;
}

// The block after settling for 0.2 s (on the floor, after a 0.1 mm fall).
Simulator landed(bool probe) {
  Simulator sim(chambers_on(probe));
  while (sim.data().time < 0.2) sim.step();
  return sim;
}

// A step's contact record for the nodes within 1e-12 m of the obstacle's surface or inside it.
struct Record {
  std::vector<int> touching;
  std::vector<Vec3> impulse{Vec3::Zero()};
  ContactStep step;
  Record(const Record&) = delete;  // the step's spans are into this one's vectors
  Record(const Model& m, const Data& d, std::span<const Vec3> x) : touching(x.size(), -1) {
    for (size_t i = 0; i < x.size(); ++i)
      if (obstacle_distance(m.obstacles[0], d.controls.obstacle_motion[0], x[i], d.time).distance <=
          1e-12)
        touching[i] = 0;
    step.x_start = d.x;
    step.start_time = d.time;
    step.dt = d.dt;
    step.touching = touching;
    step.impulse = impulse;
  }
};

double largest_difference(std::span<const Vec3> a, std::span<const Vec3> b) {
  double largest = 0.0;
  for (size_t i = 0; i < a.size(); ++i) largest = std::max(largest, (a[i] - b[i]).norm());
  return largest;
}

// The two chambers on the floor, every node given 1 cm/s down and along x: the contact's and
// the volumes' velocity stages alternated until the contact changes nothing (the reference),
// against both once, the contact again and then the held solve.
TEST(HeldVolumes, VelocitiesLandWhereTheAlternationConverges) {
  Simulator sim = landed(false);
  const Model& m = sim.model();
  Data& d = sim.data();
  std::vector<Vec3> v = d.v, grad(d.x.size());
  for (Vec3& vi : v) vi += Vec3(0.01, 0.0, -0.01);
  Record record(m, d, d.x), alternated(m, d, d.x);
  ASSERT_GT(std::count(record.touching.begin(), record.touching.end(), 0), 4);

  std::vector<Vec3> reference = v;
  int rounds = 0;
  for (double changed = 1.0; changed > 0.0 && rounds < 200; ++rounds) {
    changed = apply_contact_velocities(m, d.controls, d.x, reference, d.time, alternated.step);
    ASSERT_TRUE(project_coupled_volume_velocities(m, *d.work, d.x, reference, grad));
  }

  std::vector<Vec3> held = v;
  apply_contact_velocities(m, d.controls, d.x, held, d.time, record.step);
  ASSERT_TRUE(project_coupled_volume_velocities(m, *d.work, d.x, held, grad));
  ASSERT_GT(apply_contact_velocities(m, d.controls, d.x, held, d.time, record.step), 1e-6);
  std::vector<ObstacleContact>& resting = d.work->contacts;
  ASSERT_TRUE(resting_on_obstacles(m, d.controls, d.x, held, d.time, record.step, resting));
  ASSERT_TRUE(project_coupled_volume_velocities_held(m, *d.work, d.x, held, resting,
                                                     record.touching, record.impulse));
  const double speed = 0.01 * std::sqrt(2.0);
  const double apart = largest_difference(held, reference);
  const double impulse_error = (record.impulse[0] - alternated.impulse[0]).norm();
  std::printf(
      "held solve vs %d alternated rounds: velocities %.3g m/s apart, impulses %.6g / "
      "%.6g N s (%zu nodes held)\n",
      rounds, apart, record.impulse[0].z(), alternated.impulse[0].z(), resting.size());
  EXPECT_GT(rounds, 3);  // the alternation needs several rounds here
  EXPECT_LT(apart, 1e-13 * speed);
  EXPECT_LT(impulse_error, 1e-12 * alternated.impulse[0].norm());
  EXPECT_GT(record.impulse[0].z(), 0.0);  // the floor pushes up
  // Nothing left for the contact stage to take, and every volume rate zero.
  EXPECT_LT(apply_contact_velocities(m, d.controls, d.x, held, d.time, record.step), 1e-15 * speed);
  for (const VolumeConstraint& c : m.volumes) {
    volume_gradient(c, d.x, grad);
    double rate = 0.0, scale = 0.0;
    for (int i : c.nodes) rate += grad[i].dot(held[i]), scale += grad[i].norm() * speed;
    EXPECT_LT(std::abs(rate), 1e-13 * scale) << c.component;
  }
}

// The positions: the block moved 0.1 mm into the obstacle, projected by contact and volumes
// alternated (a hundred rounds) against the held chord steps. On the floor the held nodes
// slide in its plane and stay on it exactly; on the cylinder they leave its surface by the
// square of their slide over its diameter, which the next contact stage takes back.
TEST(HeldVolumes, PositionsLandWhereTheAlternationConverges) {
  for (bool probe : {false, true}) {
    Simulator sim = landed(probe);
    const Model& m = sim.model();
    Data& d = sim.data();
    std::vector<Vec3> x = d.x, grad(d.x.size());
    for (Vec3& xi : x) xi.z() -= 1e-4;
    ASSERT_TRUE(project_coupled_volumes(m, d.controls, *d.work, x, d.time, grad));  // kept
    Record record(m, d, x), alternated(m, d, x);

    std::vector<Vec3> reference = x;
    for (int round = 0; round < 100; ++round) {
      apply_contacts(m, d.controls, reference, d.time, alternated.step);
      ASSERT_TRUE(project_coupled_volumes(m, d.controls, *d.work, reference, d.time, grad));
    }
    ASSERT_TRUE(project_coupled_volumes(m, d.controls, *d.work, x, d.time, grad));
    std::vector<Vec3> held = x;
    apply_contacts(m, d.controls, held, d.time, record.step);
    ASSERT_TRUE(project_coupled_volumes(m, d.controls, *d.work, held, d.time, grad));
    const double moved = apply_contacts(m, d.controls, held, d.time, record.step);
    std::vector<ObstacleContact>& on = d.work->contacts;
    ASSERT_TRUE(on_obstacles(m, d.controls, held, d.time, record.step, on));
    const std::vector<Vec3> before = held;
    ASSERT_TRUE(reproject_coupled_volumes_held(m, d.controls, *d.work, held, d.time, on,
                                               record.touching, record.impulse, d.dt));
    double deepest = 0.0, worst_volume = 0.0;
    for (const Vec3& xi : held)
      deepest = std::min(
          deepest,
          obstacle_distance(m.obstacles[0], d.controls.obstacle_motion[0], xi, d.time).distance);
    for (const VolumeConstraint& c : m.volumes)
      worst_volume = std::max(worst_volume,
                              std::abs(enclosed_volume(held, c.triangles) / c.target_volume - 1.0));
    const double apart = largest_difference(held, reference);
    const double slide = largest_difference(held, before);
    std::printf(
        "%s: second contact stage %.3g m, held nodes %zu, slide %.3g m, deepest %.3g m, "
        "volumes %.3g, %.3g m from the rounds' limit\n",
        probe ? "cylinder" : "floor", moved, on.size(), slide, -deepest, worst_volume, apart);
    EXPECT_GT(moved, 1e-9);  // the volumes' projection did push nodes back in
    EXPECT_LT(worst_volume, 1e-12);
    // A slide s along a surface of radius r leaves it by s^2 / 2r (r = 15 mm).
    EXPECT_GT(deepest, probe ? -slide * slide / (2 * 0.015) - 1e-15 : -1e-15);
    // Both land on the volumes and the obstacle, along directions from linearisations a
    // move apart (each round's own, the first projection's): to second order in that move
    // over the block's size (2 cm).
    EXPECT_LT(apart, moved * moved / 0.02);
  }
}

// Whole steps on the probe take the held path, then FIRE: the block comes to rest, its weight
// carried by the probe and its top face together, and a step from that rest gives the probe
// the impulse of that force (the held nodes' given-back pushes included). FIRE stops at 1e-6
// N here (a node on a curved obstacle and a kept surface, as in the prostate study), so each
// sum over the free nodes is within their number times the residual.
TEST(HeldVolumes, ChambersOnAProbeRelaxToRestOnTheirWeight) {
  Simulator sim = landed(true);
  const Model& m = sim.model();
  const StaticResult relaxed = sim.relax(sim.data().time, 200000);
  ASSERT_TRUE(relaxed.converged);
  double weight = 0.0;
  int free_nodes = 0;
  for (int i = 0; i < m.node_count(); ++i)
    weight += m.mass[size_t(i)] * 9.81, free_nodes += m.inverse_mass[size_t(i)].norm() > 0.0;
  const double bound = free_nodes * relaxed.residual;
  const Vec3 contact = obstacle_force(m, sim.data(), 0);
  Vec3 held = Vec3::Zero();
  for (const Vec3& r : sim.support_reactions()) held += r;
  sim.step();
  const Vec3 stepped = sim.data().contact_force.at(0);
  std::printf(
      "chambers on a probe: relaxed to %.3g N in %ld iterations, probe %.9g N (a step's "
      "impulse / dt %.9g N), top %.9g N, weight %.9g N\n",
      relaxed.residual, relaxed.iterations, contact.z(), stepped.z(), held.z(), weight);
  EXPECT_GT(contact.z(), 0.1 * weight);  // the probe carries a real share
  EXPECT_NEAR(contact.z() + held.z(), weight, bound);
  EXPECT_NEAR(stepped.z(), contact.z(), bound);
}

}  // namespace
}  // namespace phymul
