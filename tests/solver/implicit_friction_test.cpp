// Coulomb friction on rigid obstacles in implicit steps, against Coulomb's law for a block
// (held on a gentle slope, sliding on a steep one at g (sin theta - mu cos theta), a thrown
// block stopping where backward Euler's steps of a particle say), as the explicit steps are
// tested in tests/constraints/friction_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "phymul/simulation.hpp"
#include "solver/implicit_step.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kG = 9.81;
constexpr double kTolerance = 1e-9;  // N, each step's residual
constexpr double kDt = 2e-3;         // s, about 40 times the explicit limit of the block

// A stiff 2 cm cube of 3^3 nodes resting on the rough plane z = 0, on a slope of angle theta:
// the plane stays horizontal and gravity is tilted.
Model block_on_slope(double theta, double friction, bool tangential_gravity = true,
                     const Schedule& floor_motion = {}) {
  Model model;
  add_elastic_component(
      model, "block", make_box(Vec3(0.02, 0.02, 0.02), {2, 2, 2}, CellType::hexa, Vec3(0, 0, 0.01)),
      testing::material(400.0));
  RigidObstacle plane;
  plane.shape = RigidObstacle::Shape::plane;
  plane.axis = Vec3::UnitZ();
  plane.friction = friction;
  plane.motion = floor_motion;
  add_rigid_obstacle(model, plane);
  model.gravity = kG * Vec3(tangential_gravity ? std::sin(theta) : 0.0, 0.0, -std::cos(theta));
  model.settings.integrator = Integrator::implicit;
  model.settings.implicit_iterations = 200;
  model.settings.implicit_tolerance = kTolerance;
  finalize(model);
  return model;
}

double total_mass(const Model& m) {
  double sum = 0.0;
  for (double mi : m.mass) sum += mi;
  return sum;
}

Vec3 centre_velocity(const Simulator& sim) {
  Vec3 p = Vec3::Zero();
  for (int i = 0; i < sim.model().node_count(); ++i) p += sim.model().mass[i] * sim.data().v[i];
  return p / total_mass(sim.model());
}

Vec3 centre(const Simulator& sim) {
  Vec3 c = Vec3::Zero();
  for (int i = 0; i < sim.model().node_count(); ++i) c += sim.model().mass[i] * sim.data().x[i];
  return c / total_mass(sim.model());
}

// The block settled under the normal part of gravity by implicit steps, then the slope's
// tangential part switched on at t = 0 (with `speed` m/s along x given to every node).
Simulator settled_on_slope(double theta, double friction, double speed = 0.0,
                           const Schedule& floor_motion = {}) {
  Simulator flat(block_on_slope(theta, friction, false));
  flat.set_dt(kDt);
  for (int k = 0; k < 200; ++k) flat.step();
  EXPECT_LT(centre_velocity(flat).norm(), 1e-6);
  Simulator sim(block_on_slope(theta, friction, true, floor_motion));
  sim.set_dt(kDt);
  const Controls controls = sim.data().controls;  // the floor's motion
  sim.data() = flat.data();
  sim.data().controls = controls;
  sim.data().time = sim.data().load_time = 0.0;
  for (Vec3& v : sim.data().v) v.x() += speed;
  return sim;
}

// Steps to `end` s, each converged to the tolerance.
void run_to(Simulator& sim, double end, int* most = nullptr) {
  while (sim.data().time < end - 1e-12) {
    sim.step();
    ASSERT_LE(implicit_residual_force(sim.data()), kTolerance) << "t = " << sim.data().time;
    if (most) *most = std::max(*most, implicit_iterations(sim.data()));
  }
}

TEST(ImplicitFriction, BlockOnAGentleSlopeStays) {
  const double theta = 10.0 * kPi / 180.0, mu = 0.3;  // tan theta = 0.176 < mu
  Simulator sim = settled_on_slope(theta, mu);
  const Vec3 start = centre(sim);
  int most = 0;
  run_to(sim, 0.5, &most);
  const double early = (centre(sim) - start).x();
  run_to(sim, 1.0, &most);
  const double late = (centre(sim) - start).x();
  const double mass = total_mass(sim.model());
  const Vec3 force = sim.data().contact_force[0];
  std::printf(
      "gentle slope: centre moved %.3g m by 0.5 s, %.3g m more by 1 s; friction %.9g N, "
      "M g sin %.9g N; at most %d solves a step\n",
      early, late - early, -force.x(), mass * kG * std::sin(theta), most);
  // Frictionless, it would slide g sin(theta) t^2 / 2 = 0.85 m in 1 s. The sudden tilt rocks
  // the block: its unloaded up-slope corners slip tens of micrometres at first (as in the
  // explicit steps), then nothing moves.
  EXPECT_LT(early, 1e-4);
  EXPECT_LT(std::abs(late - early), 1e-8);
  // At rest the obstacle holds the weight: along the slope the static friction, across it
  // the normal force, each to the residual left on the 9 touching nodes.
  EXPECT_NEAR(-force.x(), mass * kG * std::sin(theta), 9 * kTolerance);
  EXPECT_NEAR(force.z(), mass * kG * std::cos(theta), 9 * kTolerance);
  EXPECT_LE(-force.x(), mu * force.z());
}

// The centre's acceleration along the slope over 0.3 s: the least-squares slope of its
// velocity against time.
double sliding_acceleration(double theta, double mu) {
  Simulator sim = settled_on_slope(theta, mu);
  double n = 0, st = 0, sv = 0, stt = 0, stv = 0;
  while (sim.data().time < 0.3 - 1e-12) {
    run_to(sim, sim.data().time + kDt);
    const double t = sim.data().time, v = centre_velocity(sim).x();
    n += 1, st += t, sv += v, stt += t * t, stv += t * v;
  }
  return (n * stv - st * sv) / (n * stt - st * st);
}

TEST(ImplicitFriction, BlockOnASteepSlopeSlidesWithTheCoulombAcceleration) {
  const double theta = 30.0 * kPi / 180.0, mu = 0.3;                      // tan theta = 0.577 > mu
  const double expected = kG * (std::sin(theta) - mu * std::cos(theta));  // 2.356 m/s^2
  const double measured = sliding_acceleration(theta, mu);
  const double free = sliding_acceleration(theta, 0.0);
  std::printf("steep slope: acceleration %.6f m/s^2 (analytic %.6f), frictionless %.6f (%.6f)\n",
              measured, expected, free, kG * std::sin(theta));
  // A uniform acceleration is exact in backward Euler's velocities.
  EXPECT_NEAR(measured, expected, 1e-3 * expected);
  EXPECT_NEAR(free, kG * std::sin(theta), 1e-3 * kG * std::sin(theta));
}

// Thrown at 0.5 m/s on a level rough floor: it slows at mu g and stops. Backward Euler's steps
// of a particle slow it by h mu g a step and move it by h times the new speed, until a step
// would turn it back: there it sticks.
TEST(ImplicitFriction, AThrownBlockStopsWhereCoulombSays) {
  const double mu = 0.3, v0 = 0.5, a = mu * kG;
  Simulator sim = settled_on_slope(0.0, mu, v0);
  const Vec3 start = centre(sim);
  double particle = 0.0;
  for (double v = v0 - a * kDt; v > 0.0; v -= a * kDt) particle += kDt * v;
  int most = 0;
  run_to(sim, 0.4, &most);  // it stops near v0 / a = 0.17 s
  const double stopped = (centre(sim) - start).x();
  run_to(sim, 0.6, &most);
  const double later = (centre(sim) - start).x();
  std::printf(
      "thrown: stopped after %.6f m (particle %.6f m, continuous %.6f m), %.3g m more "
      "by 0.6 s, at most %d solves a step\n",
      stopped, particle, v0 * v0 / (2 * a), later - stopped, most);
  // The block is no particle: it tips forward as it slows, and its rocking when it stops
  // moves its centre a little.
  EXPECT_NEAR(stopped, particle, 0.01 * particle);
  // Stopped: 0.1 m further at the throw's speed.
  EXPECT_LT(std::abs(later - stopped), 1e-6);
}

// On a level rough floor that starts moving at 0.2 m/s, the block is dragged at mu g until
// it moves with the floor, then carried: friction relative to a moving shape.
TEST(ImplicitFriction, AMovingRoughFloorCarriesTheBlockAlong) {
  const double mu = 0.3, speed = 0.2, a = mu * kG;
  const Schedule floor{{0.0, 10.0}, {Vec3::Zero(), Vec3(10.0 * speed, 0.0, 0.0)}};
  Simulator sim = settled_on_slope(0.0, mu, 0.0, floor);
  const Vec3 start = centre(sim);
  double particle = 0.0;
  for (double v = 0.0, t = 0.0; t < 0.3 - 1e-12; t += kDt) {
    v = std::min(v + a * kDt, speed);
    particle += kDt * v;
  }
  int most = 0;
  run_to(sim, 0.3, &most);  // it catches up near speed / a = 0.068 s
  const double moved = (centre(sim) - start).x();
  const double velocity = centre_velocity(sim).x();
  std::printf(
      "moving floor: block moved %.6f m (particle %.6f m), at %.9f m/s (floor %.3f), at "
      "most %d solves a step\n",
      moved, particle, velocity, speed, most);
  EXPECT_NEAR(moved, particle, 0.01 * particle);
  // Carried at the floor's speed, but for the block's rocking since it caught up (the
  // frictionless block stays at rest).
  EXPECT_NEAR(velocity, speed, 1e-5 * speed);
}

}  // namespace
}  // namespace phymul
