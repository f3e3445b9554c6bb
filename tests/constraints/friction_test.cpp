// Coulomb friction against rigid obstacles, and the contact force the monitors report.
#include <gtest/gtest.h>

#include <cmath>

#include "constraints/contact.hpp"
#include "phymul/simulation.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

using Shape = RigidObstacle::Shape;

constexpr double kPi = 3.14159265358979323846;
constexpr double kG = 9.81;

RigidObstacle floor_plane(double friction) {
  RigidObstacle o;
  o.shape = Shape::plane;
  o.axis = Vec3::UnitZ();
  o.friction = friction;
  return o;
}

// A stiff 2 cm cube resting on the plane z = 0, on a slope of angle theta: the plane stays
// horizontal and gravity is tilted (the same physics, simpler geometry).
Simulator block_on_slope(double theta, double friction, double height = 0.0,
                         bool tangential_gravity = true) {
  Model model;
  add_elastic_component(
      model, "block",
      make_box(Vec3(0.02, 0.02, 0.02), {2, 2, 2}, CellType::hexa, Vec3(0, 0, 0.01 + height)),
      testing::material(400.0));
  add_rigid_obstacle(model, floor_plane(friction));
  model.gravity = kG * Vec3(tangential_gravity ? std::sin(theta) : 0.0, 0.0, -std::cos(theta));
  model.settings.tolerance = 1e-10;
  finalize(model);
  return Simulator(model);
}

// The block first settled under the normal part of gravity (no bounce left), then the slope's
// tangential part switched on at t = 0.
Simulator settled_on_slope(double theta, double friction) {
  Simulator flat = block_on_slope(theta, friction, 0.0, false);
  EXPECT_TRUE(flat.relax(0.0, 100000).converged);
  Simulator sim = block_on_slope(theta, friction);
  sim.data() = flat.data();
  sim.data().time = 0.0;
  return sim;
}

Vec3 momentum(const Simulator& sim) {
  Vec3 p = Vec3::Zero();
  for (int i = 0; i < sim.model().node_count(); ++i) p += sim.model().mass[i] * sim.data().v[i];
  return p;
}

double total_mass(const Model& m) {
  double sum = 0.0;
  for (double mi : m.mass) sum += mi;
  return sum;
}

// Centre-of-mass acceleration along the slope over 0.3 s: the least-squares slope of its
// velocity against time, which averages out the block's undamped elastic vibration.
double sliding_acceleration(double theta, double mu, double* base_slip = nullptr) {
  Simulator sim = settled_on_slope(theta, mu);
  const double mass = total_mass(sim.model());
  double n = 0, st = 0, sv = 0, stt = 0, stv = 0;
  while (sim.data().time < 0.3 - 1e-12) {
    sim.step();
    const double t = sim.data().time, v = momentum(sim).x() / mass;
    n += 1, st += t, sv += v, stt += t * t, stv += t * v;
  }
  if (base_slip) {
    *base_slip = 0.0;
    for (int i = 0; i < sim.model().node_count(); ++i)
      if (sim.model().rest_position[i].z() == 0.0)
        *base_slip = std::max(*base_slip, sim.data().x[i].x() - sim.model().rest_position[i].x());
  }
  return (n * stv - st * sv) / (n * stt - st * st);
}

double largest_base_slip(const Simulator& sim, const std::vector<Vec3>& start) {
  double slip = 0.0;
  for (int i = 0; i < sim.model().node_count(); ++i)
    if (sim.model().rest_position[i].z() == 0.0)
      slip = std::max(slip, (sim.data().x[i] - start[i]).head<2>().norm());
  return slip;
}

TEST(Friction, BlockOnAGentleSlopeStays) {
  const double theta = 10.0 * kPi / 180.0, mu = 0.3;  // tan theta = 0.176 < mu
  Simulator sim = settled_on_slope(theta, mu);
  const std::vector<Vec3> settled = sim.data().x;
  // The sudden tilt rocks the undamped block: its unloaded up-slope corners slip a few
  // tens of micrometres in the first instants, then (nearly) nothing moves any more.
  while (sim.data().time < 0.5) sim.step();
  const double early = largest_base_slip(sim, settled);
  const Vec3 p_early = momentum(sim);
  double late = 0.0, steps = 0;
  Vec3 impulse = Vec3::Zero();
  while (sim.data().time < 2.0) {
    sim.step();
    late = std::max(late, largest_base_slip(sim, settled));
    impulse += sim.data().contact_force[0] * sim.dt();
    ++steps;
  }
  const double mass = total_mass(sim.model());
  const double span = steps * sim.dt();
  const Vec3 mean_force = impulse / span;
  std::printf(
      "gentle slope: base slip %.3g m at 0.5 s, %.3g m by 2 s; mean friction %.6g N, "
      "M g sin(theta) %.6g N\n",
      early, late, mean_force.x(), mass * kG * std::sin(theta));
  EXPECT_LT(early, 1e-4);
  // Held: the corners' creep nearly stops once the rocking settled in (measured 48 nm in
  // 1.5 s, where sliding without friction would go 1.9 m).
  EXPECT_LT(late - early, 1e-6);
  // Static friction supplies what holds the block: the momentum balance over 1.5 s.
  const double pull = mass * kG * std::sin(theta);
  EXPECT_NEAR(-mean_force.x(), pull - (momentum(sim) - p_early).x() / span, 1e-9 * pull);
  EXPECT_LT(std::abs((momentum(sim) - p_early).x()) / span, 0.05 * pull);
}

TEST(Friction, BlockOnASteepSlopeSlidesWithTheCoulombAcceleration) {
  const double theta = 30.0 * kPi / 180.0, mu = 0.3;                      // tan theta = 0.577 > mu
  const double expected = kG * (std::sin(theta) - mu * std::cos(theta));  // 2.356 m/s^2
  double slip = 0.0;
  const double measured = sliding_acceleration(theta, mu, &slip);
  std::printf("steep slope: acceleration %.6f m/s^2, analytic %.6f m/s^2\n", measured, expected);
  EXPECT_NEAR(measured, expected, 1e-3 * expected);
  EXPECT_GT(slip, 0.05);  // it slid: 0.5 a t^2 = 0.1 m
  // Frictionless, the same block slides at g sin theta.
  const double free = sliding_acceleration(theta, 0.0);
  EXPECT_NEAR(free, kG * std::sin(theta), 1e-3 * kG * std::sin(theta));
}

// The monitored contact force is the momentum the obstacle gives over each step: with
// gravity the only other external force (internal forces cancel with the reaction form),
// the body's momentum change over a step is (M g + F_contact) dt, step by step.
TEST(ContactForce, IsTheMomentumTheObstacleGivesEveryStep) {
  // Dropped from 1 mm onto a rough slope: it lands, bounces and slides, so the force has
  // normal and friction parts and varies from step to step.
  Simulator sim = block_on_slope(30.0 * kPi / 180.0, 0.3, 0.001);
  const Model& model = sim.model();
  const double mass = total_mass(model);
  double largest = 0.0, worst = 0.0;
  for (int k = 0; k < 400; ++k) {
    const Vec3 p0 = momentum(sim);
    sim.step();
    const Vec3 expected = (momentum(sim) - p0) / sim.dt() - mass * model.gravity;
    const Vec3 force = sim.data().contact_force[0];
    largest = std::max(largest, force.norm());
    worst = std::max(worst, (force - expected).norm());
  }
  std::printf("contact force: largest %.4g N, worst momentum mismatch %.3g N (weight %.4g N)\n",
              largest, worst, mass * kG);
  EXPECT_GT(largest, mass * kG);  // the landing
  EXPECT_LT(worst, 1e-9 * largest);
}

TEST(ContactForce, AtRestEqualsTheWeightAndObstacleForce) {
  Model model;
  add_elastic_component(
      model, "box", make_box(Vec3(0.02, 0.02, 0.02), {3, 3, 3}, CellType::hexa, Vec3(0, 0, 0.0105)),
      testing::material(30.0));
  add_rigid_obstacle(model, floor_plane(0.0));
  model.gravity = Vec3(0, 0, -kG);
  model.damping = 20.0;
  model.settings.tolerance = 1e-11;
  finalize(model);
  Simulator sim(model);
  const double weight = total_mass(model) * kG;
  while (sim.data().time < 1.5) sim.step();  // damped dynamics settle
  const Vec3 settled = sim.data().contact_force[0];
  ASSERT_TRUE(sim.relax(sim.data().time, 200000).converged);
  const Vec3 relaxed = sim.data().contact_force[0];
  const Vec3 balance = obstacle_force(sim.model(), sim.data(), 0);
  std::printf(
      "at rest: dynamics %.12g N, relaxed %.12g N, obstacle_force %.12g N, weight %.12g N\n",
      settled.z(), relaxed.z(), balance.z(), weight);
  EXPECT_NEAR(settled.z(), weight, 1e-6 * weight);
  // Relaxed until every node's residual is below the tolerance: their sum bounds the error.
  EXPECT_NEAR(relaxed.z(), weight, model.node_count() * model.settings.tolerance);
  EXPECT_LT((relaxed - balance).norm(), 1e-9 * weight);
  EXPECT_LT(relaxed.head<2>().norm(), 1e-9 * weight);
}

TEST(ContactForce, ProbeForceAgreesWithObstacleForceAndSupports) {
  Model model;
  const int c = add_elastic_component(model, "block",
                                      make_box(Vec3(0.02, 0.02, 0.01), {4, 4, 2}, CellType::hexa),
                                      testing::material(20.0));
  add_fixed_nodes(model, model.components[c].node_sets.at("top"));
  RigidObstacle probe;
  probe.shape = Shape::probe;
  probe.point = Vec3(0.002, 0.001, -0.009);
  probe.radius = 0.004;
  probe.motion = Schedule{{0.0, 1.0}, {Vec3::Zero(), Vec3(0, 0, 0.003)}};
  add_rigid_obstacle(model, probe);
  model.settings.tolerance = 1e-12;
  finalize(model);
  Simulator sim(model);
  ASSERT_TRUE(sim.relax(1.0, 200000).converged);
  const Vec3 monitored = sim.data().contact_force[0];
  const Vec3 balance = obstacle_force(sim.model(), sim.data(), 0);
  Vec3 support = Vec3::Zero();
  for (const Vec3& r : sim.support_reactions()) support += r;
  std::printf("probe: monitored (%.9g %.9g %.9g) N, obstacle_force (%.9g %.9g %.9g) N\n",
              monitored.x(), monitored.y(), monitored.z(), balance.x(), balance.y(), balance.z());
  EXPECT_GT(monitored.z(), 0.0);
  EXPECT_LT((monitored - balance).norm(), 1e-6 * balance.norm());
  EXPECT_LT((monitored + support).norm(), 1e-6 * balance.norm());
}

}  // namespace
}  // namespace phymul
