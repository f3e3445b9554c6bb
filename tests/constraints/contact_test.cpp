#include "constraints/contact.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "support/kernels.hpp"
#include "support/models.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

using Shape = RigidObstacle::Shape;

RigidObstacle shape(Shape kind, const Vec3& point, const Vec3& axis, double radius = 0.0,
                    double length = 0.0) {
  return testing::obstacle(kind, point, axis, radius, length);
}

void expect_vec_near(const Vec3& a, const Vec3& b, double tol) {
  EXPECT_LE((a - b).norm(), tol) << a.transpose() << " vs " << b.transpose();
}

TEST(ContactGeometry, Plane) {
  const RigidObstacle o = shape(Shape::plane, Vec3(0, 0, 1), Vec3(0, 0, 2));
  EXPECT_DOUBLE_EQ(obstacle_distance(o, Vec3(3, 4, 1.5), 0).distance, 0.5);
  EXPECT_DOUBLE_EQ(obstacle_distance(o, Vec3(3, 4, 0.25), 0).distance, -0.75);
  expect_vec_near(closest_surface_point(o, Vec3(3, 4, 0.25), 0), Vec3(3, 4, 1), 1e-15);
  expect_vec_near(obstacle_distance(o, Vec3(3, 4, 0.25), 0).normal, Vec3::UnitZ(), 0);
}

TEST(ContactGeometry, SphereFollowsItsMotion) {
  RigidObstacle o = shape(Shape::sphere, Vec3(1, 0, 0), Vec3::UnitZ(), 0.5);
  o.motion = Schedule{{0.0, 2.0}, {Vec3::Zero(), Vec3(0, 2, 0)}};
  EXPECT_DOUBLE_EQ(obstacle_distance(o, Vec3(1, 1, 0.25), 1.0).distance, -0.25);  // centre (1,1,0)
  expect_vec_near(closest_surface_point(o, Vec3(1, 1, 0.25), 1.0), Vec3(1, 1, 0.5), 1e-15);
  EXPECT_DOUBLE_EQ(obstacle_distance(o, Vec3(4, 1, 0), 1.0).distance, 2.5);
  // The centre itself: any direction is closest; the point lands on the surface.
  const Vec3 c = closest_surface_point(o, Vec3(1, 1, 0), 1.0);
  EXPECT_NEAR((c - Vec3(1, 1, 0)).norm(), 0.5, 1e-15);
}

TEST(ContactGeometry, CapsuleSideEndsAndAxis) {
  const RigidObstacle o = shape(Shape::capsule, Vec3::Zero(), Vec3::UnitZ(), 0.1, 1.0);
  // Beside the segment: radial.
  EXPECT_NEAR(obstacle_distance(o, Vec3(0.05, 0, 0.5), 0).distance, -0.05, 1e-15);
  expect_vec_near(closest_surface_point(o, Vec3(0.05, 0, 0.5), 0), Vec3(0.1, 0, 0.5), 1e-15);
  // Near the far tip and behind the base: both ends are hemispheres.
  expect_vec_near(closest_surface_point(o, Vec3(0, 0, 1.05), 0), Vec3(0, 0, 1.1), 1e-15);
  expect_vec_near(closest_surface_point(o, Vec3(0, 0, -0.02), 0), Vec3(0, 0, -0.1), 1e-15);
  EXPECT_NEAR(obstacle_distance(o, Vec3(0, 0, -0.5), 0).distance, 0.4, 1e-15);
  const Vec3 tip = Vec3(0.06, 0, 1.08);  // on the tip's hemisphere side, inside
  const Vec3 q = closest_surface_point(o, tip, 0);
  EXPECT_NEAR((q - Vec3(0, 0, 1)).norm(), 0.1, 1e-15);
  expect_vec_near((q - Vec3(0, 0, 1)).normalized(), (tip - Vec3(0, 0, 1)).normalized(), 1e-15);
  // On the axis: any radial direction is closest.
  const Vec3 a = closest_surface_point(o, Vec3(0, 0, 0.3), 0);
  EXPECT_NEAR(a.z(), 0.3, 1e-15);
  EXPECT_NEAR(a.head<2>().norm(), 0.1, 1e-15);
}

TEST(ContactGeometry, RoundedCylinderIsOpenBackwards) {
  // A probe along +y from (0,-1,0), 0.5 long, radius 0.1: its tip centre is at (0,-0.5,0).
  const RigidObstacle o = shape(Shape::probe, Vec3(0, -1, 0), Vec3::UnitY(), 0.1, 0.5);
  // Far behind the base it is still a cylinder (a capsule would end there).
  EXPECT_NEAR(obstacle_distance(o, Vec3(0, -50, 0.02), 0).distance, -0.08, 1e-14);
  expect_vec_near(closest_surface_point(o, Vec3(0, -50, 0.02), 0), Vec3(0, -50, 0.1), 1e-14);
  EXPECT_NEAR(obstacle_distance(o, Vec3(0.3, -3, 0), 0).distance, 0.2, 1e-15);
  // Near the rounded tip.
  expect_vec_near(closest_surface_point(o, Vec3(0, -0.45, 0), 0), Vec3(0, -0.4, 0), 1e-15);
  EXPECT_NEAR(obstacle_distance(o, Vec3(0, -0.3, 0), 0).distance, 0.1, 1e-15);
  const Vec3 q = closest_surface_point(o, Vec3(0.03, -0.46, 0.04), 0);
  EXPECT_NEAR((q - Vec3(0, -0.5, 0)).norm(), 0.1, 1e-15);
}

TEST(ContactProjection, MovesOnlyAlongFreeAxes) {
  const RigidObstacle sphere = shape(Shape::sphere, Vec3::Zero(), Vec3::UnitZ(), 1.0);
  std::vector<Vec3> x{Vec3(0.3, 0.4, 0.1), Vec3(0.3, 0.4, 0.1), Vec3(0.3, 0.4, 0.1)};
  const std::vector<Vec3> w{Vec3::Ones(), Vec3(0, 0, 1), Vec3::Zero()};
  project_obstacle(sphere, w, x, 0.0);
  expect_vec_near(x[0], Vec3(0.3, 0.4, 0.1) / Vec3(0.3, 0.4, 0.1).norm(), 1e-15);  // closest
  EXPECT_EQ(x[1].x(), 0.3);  // only z may move: up to the surface
  EXPECT_EQ(x[1].y(), 0.4);
  EXPECT_NEAR(x[1].z(), std::sqrt(0.75), 1e-15);  // a Newton step alone would overshoot
  EXPECT_GE(obstacle_distance(sphere, x[1], 0.0).distance, 0.0);
  EXPECT_EQ(x[2], Vec3(0.3, 0.4, 0.1));  // fully held: left alone
  // A node whose normal has no free component cannot get out: it is left where it is.
  std::vector<Vec3> stuck{Vec3(0.3, 0.4, 0.0)};
  project_obstacle(sphere, std::vector<Vec3>{Vec3(0, 0, 1)}, stuck, 0.0);
  EXPECT_EQ(stuck[0], Vec3(0.3, 0.4, 0.0));
}

TEST(ContactProjection, KeepInsideHoldsNodesInAContainer) {
  RigidObstacle box_wall = shape(Shape::sphere, Vec3::Zero(), Vec3::UnitZ(), 1.0);
  box_wall.keep_inside = true;
  std::vector<Vec3> x{Vec3(0, 0, 2), Vec3(0, 0.5, 0)};
  const std::vector<Vec3> w(2, Vec3::Ones());
  project_obstacle(box_wall, w, x, 0.0);
  expect_vec_near(x[0], Vec3(0, 0, 1), 1e-15);
  EXPECT_EQ(x[1], Vec3(0, 0.5, 0));
}

// The explicit step's position stage (apply_contacts with a ContactStep: friction and the
// records) against the plain projection the implicit step, the static solver and the start
// of a run take: without friction they move every node to the same bits, and the records
// say which obstacle moved it and the momentum m dx / dt it gave.
TEST(ContactProjection, StepStageWithoutFrictionIsThePlainProjection) {
  Model model;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 400;
  for (int i = 0; i < n; ++i) {
    model.rest_position.push_back(testing::random_vec3(u, rng));
    model.mass.push_back(0.5 + 0.5 * (u(rng) + 1.0));
    // Every fourth node held on one axis, every tenth on all: the projection keeps to the rest.
    Vec3 w = Vec3::Constant(1.0 / model.mass.back());
    if (i % 4 == 1) w[i % 3] = 0.0;
    if (i % 10 == 3) w.setZero();
    model.inverse_mass.push_back(w);
  }
  model.obstacles = {shape(Shape::sphere, Vec3(0.2, 0, 0), Vec3::UnitZ(), 0.5),
                     shape(Shape::capsule, Vec3(-0.5, -0.5, -0.5), Vec3(1, 1, 1), 0.3, 1.0),
                     shape(Shape::plane, Vec3(0, 0, -0.6), Vec3(0.1, 0.2, 1.0)),
                     shape(Shape::probe, Vec3(0, 0.7, 0), Vec3(0, 1, 0), 0.2)};
  RigidObstacle container = shape(Shape::sphere, Vec3::Zero(), Vec3::UnitZ(), 1.5);
  container.keep_inside = true;
  model.obstacles.push_back(container);
  model.obstacles[1].nodes = {1, 5, 8, 13, 21, 34, 55, 89, 144, 233, 377};
  Controls controls;
  for (const RigidObstacle& o : model.obstacles) controls.obstacle_motion.push_back(o.motion);
  controls.obstacle_motion[0] = Schedule{{0.0, 1.0}, {Vec3::Zero(), Vec3(0.1, 0.2, 0.0)}};

  std::vector<Vec3> plain = model.rest_position;
  apply_contacts(model, controls, plain, 0.5);
  std::vector<Vec3> staged = model.rest_position;
  std::vector<int> touching(size_t(n), -1);
  std::vector<Vec3> impulse(model.obstacles.size(), Vec3::Zero());
  ContactStep step;
  step.x_start = model.rest_position;
  step.start_time = 0.4;
  step.dt = 0.1;
  step.touching = touching;
  step.impulse = impulse;
  apply_contacts(model, controls, staged, 0.5, step);

  // Every move is recorded: the momenta the obstacles gave add up to the nodes' m dx / dt.
  int moved = 0;
  Vec3 momentum = Vec3::Zero(), given = Vec3::Zero();
  double scale = 0.0;  // N s, the sum of the nodes' momenta's magnitudes
  for (int i = 0; i < n; ++i) {
    ASSERT_EQ(staged[size_t(i)], plain[size_t(i)]) << "node " << i;
    const Vec3 dx = plain[size_t(i)] - model.rest_position[size_t(i)];
    EXPECT_EQ(touching[size_t(i)] >= 0, dx != Vec3::Zero()) << "node " << i;
    moved += dx != Vec3::Zero();
    momentum += model.mass[size_t(i)] * dx / 0.1;
    scale += model.mass[size_t(i)] * dx.norm() / 0.1;
  }
  for (const Vec3& p : impulse) given += p;
  EXPECT_GT(moved, 40);
  EXPECT_LE((given - momentum).norm(), 1e-12 * scale);
}

TEST(ContactProjection, BuilderChecksItsInput) {
  Model model = testing::single_component(
      make_box(Vec3(0.01, 0.01, 0.01), {1, 1, 1}, CellType::hexa), testing::material(1.0));
  EXPECT_THROW(add_rigid_obstacle(model, shape(Shape::sphere, Vec3::Zero(), Vec3::UnitZ(), 0.0)),
               std::invalid_argument);
  RigidObstacle bad_node = shape(Shape::plane, Vec3::Zero(), Vec3::UnitZ());
  bad_node.nodes = {8};
  EXPECT_THROW(add_rigid_obstacle(model, bad_node), std::invalid_argument);
  RigidObstacle rough = shape(Shape::plane, Vec3::Zero(), Vec3::UnitZ());
  rough.friction = -0.3;
  EXPECT_THROW(add_rigid_obstacle(model, rough), std::invalid_argument);
  RigidObstacle tilted = shape(Shape::plane, Vec3::Zero(), Vec3::UnitZ());
  tilted.axis = Vec3(0, 0, 5);
  add_rigid_obstacle(model, tilted);
  EXPECT_EQ(model.obstacles.back().axis, Vec3::UnitZ());
}

// Largest free force on the nodes that do not touch any obstacle: an independent look at
// the equilibrium relax reports.
double free_residual_off_contact(const Simulator& sim) {
  const Model& m = sim.model();
  const Data& s = sim.data();
  double largest = 0.0;
  for (int i = 0; i < m.node_count(); ++i) {
    bool touching = false;
    for (const RigidObstacle& o : m.obstacles)
      touching |= std::abs(obstacle_distance(o, s.x[i], s.time).distance) <= 1e-12;
    if (touching) continue;
    const Vec3 free = (m.inverse_mass[i].array() > 0.0).cast<double>().matrix();
    largest = std::max(largest, s.f[i].cwiseProduct(free).norm());
  }
  return largest;
}

TEST(Contact, BoxDroppedOnAPlaneNeverCrossesItAndRestsOnIt) {
  Model model;
  add_elastic_component(model, "box",
                        make_box(Vec3(0.02, 0.02, 0.02), {3, 3, 3}, CellType::hexa,
                                 Vec3(0, 0, 0.011)),  // 1 mm above the floor
                        // At 30 N/m the landing pushed the three-neighbour corners through
                        // their flat position: the box came to rest on inverted corners by a
                        // chaotic path, and relaxing it converged or not with the round-off.
                        testing::material(300.0));
  add_rigid_obstacle(model, shape(Shape::plane, Vec3::Zero(), Vec3::UnitZ()));
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 2.0;
  model.settings.tolerance = 1e-11;
  finalize(model);
  Simulator sim(model);
  double lowest = 1.0;
  for (int k = 0; k < 3000; ++k) {
    sim.step();
    for (const Vec3& x : sim.data().x) lowest = std::min(lowest, x.z());
  }
  EXPECT_GE(lowest, -1e-15);
  EXPECT_LT(lowest, 1e-12);  // it did land
  ASSERT_TRUE(sim.relax(sim.data().time, 200000).converged);
  for (const Vec3& x : sim.data().x) EXPECT_GE(x.z(), -1e-15);
  double weight = 0.0;
  for (double mass : model.mass) weight += mass * 9.81;
  const double residual = free_residual_off_contact(sim);
  const Vec3 contact = obstacle_force(sim.model(), sim.data(), 0);
  std::printf("plane: steps' lowest z %.3g m, contact %.12g N, weight %.12g N, residual %.3g N\n",
              lowest, contact.z(), weight, residual);
  EXPECT_NEAR(contact.z(), weight, 1e-6 * weight);
  EXPECT_NEAR(contact.x(), 0.0, 1e-6 * weight);
  EXPECT_NEAR(contact.y(), 0.0, 1e-6 * weight);
}

// A node on an obstacle and on a kept volume's surface takes both velocity corrections: with
// the volume's last, it kept a velocity into the obstacle and the box never came to rest
// (relaxation stalled at 2.2e-6 N, its contact 1e-4 short of the weight).
TEST(Contact, KeptVolumeOnAPlaneRelaxesToRestOnItsWeight) {
  Model model;
  const int box = add_elastic_component(
      model, "box", make_box(Vec3(0.02, 0.02, 0.02), {3, 3, 3}, CellType::hexa, Vec3(0, 0, 0.011)),
      testing::material(300.0));
  add_volume_constraint(model, box);
  add_rigid_obstacle(model, shape(Shape::plane, Vec3::Zero(), Vec3::UnitZ()));
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 2.0;
  model.settings.tolerance = 1e-11;
  finalize(model);
  Simulator sim(model);
  for (int k = 0; k < 3000; ++k) sim.step();  // it lands
  const StaticResult relaxed = sim.relax(sim.data().time, 200000);
  double weight = 0.0;
  for (double mass : model.mass) weight += mass * 9.81;
  const Vec3 contact = obstacle_force(sim.model(), sim.data(), 0);
  std::printf(
      "kept box on a plane: relaxed to %.3g N in %ld steps, contact %.12g N, weight %.12g "
      "N, kinetic energy %.3g J\n",
      relaxed.residual, relaxed.iterations, contact.z(), weight, sim.kinetic_energy());
  ASSERT_TRUE(relaxed.converged);
  EXPECT_NEAR(contact.z(), weight, 1e-6 * weight);
  // The position stage stops once the obstacle moves no node by more than a nanometre: the
  // last volume projection leaves them less than that inside (0.16 nm here).
  double deepest = 0.0;
  for (const Vec3& x : sim.data().x) deepest = std::min(deepest, x.z());
  std::printf("deepest node %.3g m inside the floor\n", -deepest);
  EXPECT_GT(deepest, -1e-9);
}

// The bladder example (a kept volume filled from 113 to 300 mL, landing on a floor) at every
// step from 0.26 to 0.56 of the stable one: with 10 1/s of damping a few of these steps ran
// away (the landing, or the full bladder), with or without the contact and volume rounds.
TEST(Contact, TheFillingBladderOnItsFloorIsStableAtEveryStepSize) {
  Scene scene = load_scene(testing::source_dir() / "examples" / "bladder_filling.yaml");
  for (double safety = 0.26; safety < 0.565; safety += 0.015) {
    scene.simulation.dt_safety = safety;
    Simulator sim(compile_scene(scene));
    double lowest = 1.0;
    try {
      while (sim.data().time < scene.simulation.duration) {
        sim.step();
        for (const Vec3& x : sim.data().x) lowest = std::min(lowest, x.z());
      }
    } catch (const InstabilityError& e) {
      ADD_FAILURE() << "dt_safety " << safety << ": " << e.what();
    }
    EXPECT_GT(lowest, -0.032 - 1e-9) << "dt_safety " << safety;  // on the floor, not in it
    EXPECT_GT(sim.data().contact_force.at(0).z(), 0.0) << "dt_safety " << safety;
  }
}

// 4 x 4 x 2 cm block, 5 mm cells, fixed on its face `fixed`.
Model soft_block(const char* fixed) {
  Model model;
  const int c = add_elastic_component(model, "block",
                                      make_box(Vec3(0.04, 0.04, 0.02), {8, 8, 4}, CellType::hexa),
                                      testing::material(20.0));
  add_fixed_nodes(model, model.components[c].node_sets.at(fixed));
  return model;
}

TEST(Contact, MovingSphereNeverHasANodeInside) {
  Model model = soft_block("bottom");
  RigidObstacle ball = shape(Shape::sphere, Vec3(0.002, -0.001, 0.019), Vec3::UnitZ(), 0.008);
  ball.motion = Schedule{{0.0, 0.2}, {Vec3::Zero(), Vec3(0, 0, -0.005)}};  // 4 mm deep
  add_rigid_obstacle(model, ball);
  model.damping = 5.0;
  finalize(model);
  Simulator sim(model);
  double deepest = 0.0;
  int touching = 0;
  while (sim.data().time < 0.3) {
    sim.step();
    for (const Vec3& x : sim.data().x)
      deepest = std::min(deepest, obstacle_distance(ball, x, sim.data().time).distance);
  }
  for (const Vec3& x : sim.data().x)
    touching += std::abs(obstacle_distance(ball, x, sim.data().time).distance) <= 1e-12;
  std::printf("sphere: %ld steps, deepest %.3g m, %d nodes touching at the end\n", sim.data().step,
              deepest, touching);
  EXPECT_GE(deepest, -1e-15);
  EXPECT_GE(touching, 3);  // measured 4
}

TEST(Contact, ProbeForceBalancesTheSupportReactions) {
  // A 2 x 2 x 1 cm block (4 x 4 x 2 cells): the one above converges too slowly for a test.
  Model model;
  const int c = add_elastic_component(model, "block",
                                      make_box(Vec3(0.02, 0.02, 0.01), {4, 4, 2}, CellType::hexa),
                                      testing::material(20.0));
  add_fixed_nodes(model, model.components[c].node_sets.at("top"));
  // Probe along +z, 4 mm radius, its tip touching the bottom face (z = -5 mm) at t = 0, then
  // pushed 3 mm up, off the block's axis so the load is not symmetric.
  RigidObstacle probe =
      shape(Shape::probe, Vec3(0.002, 0.001, -0.019), Vec3::UnitZ(), 0.004, 0.010);
  probe.motion = Schedule{{0.0, 1.0}, {Vec3::Zero(), Vec3(0, 0, 0.003)}};
  add_rigid_obstacle(model, probe);
  // Every free node within 1e-12 N of balance: summed over the block, well inside 1e-6 of
  // the contact force.
  model.settings.tolerance = 1e-12;
  finalize(model);
  Simulator sim(model);
  ASSERT_TRUE(sim.relax(1.0, 200000).converged);
  const Vec3 contact = obstacle_force(sim.model(), sim.data(), 0);
  Vec3 support = Vec3::Zero();
  for (const Vec3& r : sim.support_reactions()) support += r;
  const double residual = free_residual_off_contact(sim);
  std::printf("probe: contact (%.9g %.9g %.9g) N, supports (%.9g %.9g %.9g) N, residual %.3g N\n",
              contact.x(), contact.y(), contact.z(), support.x(), support.y(), support.z(),
              residual);
  EXPECT_GT(contact.z(), 0.0);  // the probe pushes the block up
  EXPECT_LT((contact + support).norm(), 1e-6 * contact.norm());
  for (const Vec3& x : sim.data().x) EXPECT_GE(obstacle_distance(probe, x, 1.0).distance, -1e-15);
}

}  // namespace
}  // namespace phymul
