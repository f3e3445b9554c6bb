// Contact pairs in the implicit steps and the implicit static solver: the balls of
// examples/two_balls.yaml pressed together rest on each other without entering and the
// contact's force balances both supports; free balls that collide keep their momentum.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "constraints/deformable_contact.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "solver/implicit_step.hpp"
#include "support/models.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

// Generalised winding number of a closed surface at p (Jacobson et al. 2013): 1 inside, 0
// outside, from the triangles' solid angles (Van Oosterom and Strackee 1983).
double winding(const std::vector<Triangle>& faces, const std::vector<Vec3>& x, const Vec3& p) {
  double sum = 0.0;
  for (const Triangle& t : faces) {
    const Vec3 a = x[size_t(t[0])] - p, b = x[size_t(t[1])] - p, c = x[size_t(t[2])] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double det = a.dot(b.cross(c));
    const double div = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    sum += 2.0 * std::atan2(det, div);
  }
  return sum / (4.0 * M_PI);
}

// Distance from p to a surface, over every triangle.
double distance_to(const std::vector<Triangle>& faces, const std::vector<Vec3>& x, const Vec3& p) {
  double best = INFINITY;
  for (const Triangle& t : faces) {
    const Vec3 w = closest_barycentric(p, x[size_t(t[0])], x[size_t(t[1])], x[size_t(t[2])]);
    const Vec3 q = w[0] * x[size_t(t[0])] + w[1] * x[size_t(t[1])] + w[2] * x[size_t(t[2])];
    best = std::min(best, (p - q).norm());
  }
  return best;
}

// The deepest any surface node of one side of the pair is inside the other (m, 0 if none),
// and how many nodes lie within 1e-9 m of the other surface.
std::pair<double, int> deepest(const Model& m, const std::vector<Vec3>& x) {
  const ContactPair& pair = m.contact_pairs.at(0);
  double depth = 0.0;
  int touching = 0;
  for (int side = 0; side < 2; ++side)
    for (int i : pair.nodes[size_t(side)]) {
      const std::vector<Triangle>& other = pair.faces[size_t(1 - side)];
      const double d = distance_to(other, x, x[size_t(i)]);
      if (d < 1e-9) ++touching;
      if (winding(other, x, x[size_t(i)]) > 0.5) depth = std::max(depth, d);
    }
  return {depth, touching};
}

Model two_balls(StaticSolver solver, double tolerance) {
  Scene scene = load_scene(testing::source_dir() / "examples" / "two_balls.yaml");
  scene.simulation.mode = SolveMode::static_equilibrium;
  scene.simulation.solver = solver;
  scene.simulation.tolerance = tolerance;
  scene.simulation.max_iterations = 2000000;
  return compile_scene(scene);
}

// Sum of the support reactions on one ball's nodes (N).
Vec3 held_by_supports(const Simulator& sim, int component) {
  const std::vector<Vec3> reaction = sim.support_reactions();
  Vec3 sum = Vec3::Zero();
  for (int i : sim.model().components[size_t(component)].nodes) sum += reaction[size_t(i)];
  return sum;
}

// (Kinetic relaxation does not settle this scene: its pair projection left 1.8e-3 N after two
// million iterations.)
TEST(ImplicitPairs, PressedBallsRestOnEachOtherBalanced) {
  Simulator implicit(two_balls(StaticSolver::implicit, 1e-10));
  const StaticResult r = implicit.solve_static();
  ASSERT_TRUE(r.converged) << r.residual;
  const Model& m = implicit.model();
  const auto [depth, touching] = deepest(m, implicit.data().x);
  EXPECT_LT(depth, 1e-9);  // no node inside the other ball (a hair's round-off)
  EXPECT_GE(touching, 1);
  // The right ball's push on the left one, against each ball's support: the left's moved cap
  // holds it back, the right's fixed cap takes it.
  const Vec3 push = implicit.data().pair_contact_force[0];
  EXPECT_LT(push.x(), -0.01);  // the right ball pushes the left one back
  const Vec3 left = held_by_supports(implicit, 0), right = held_by_supports(implicit, 1);
  EXPECT_LT((left + push).norm(), 1e-8) << left.transpose() << " / " << push.transpose();
  EXPECT_LT((right - push).norm(), 1e-8) << right.transpose();

  std::printf("%d implicit static steps, push %.6g N, %d nodes on the other ball\n",
              int(r.iterations), push.x(), touching);
}

// Two free balls, no gravity, no damping: the left one thrown at the right one at 0.2 m/s.
// Through the collision (implicit steps of 1 ms, 30 times the explicit limit's order) the
// total momentum stays, the right ball takes most of it, and no node enters the other ball.
TEST(ImplicitPairs, FreeBallsCollideKeepingTheirMomentum) {
  Model model;
  const MaterialSpec soft = testing::material(100.0);
  const int left = add_elastic_component(
      model, "left", make_ellipsoid_volume({0.01, 0.01, 0.01}, 2, 2, Vec3(-0.0105, 0, 0)), soft);
  const int right = add_elastic_component(
      model, "right", make_ellipsoid_volume({0.01, 0.01, 0.01}, 2, 2, Vec3(0.0105, 0.002, 0)),
      soft);
  add_contact_pair(model, left, right);
  model.damping = 0.0;
  model.settings.integrator = Integrator::implicit;
  model.settings.implicit_iterations = 500;
  model.settings.implicit_tolerance = 1e-10;
  model.settings.dt = 1e-3;
  finalize(model);
  Simulator sim(model);
  for (int i : model.components[size_t(left)].nodes) sim.data().v[size_t(i)] = Vec3(0.2, 0, 0);
  auto momentum = [&](int c) {
    Vec3 p = Vec3::Zero();
    for (int i : model.components[size_t(c)].nodes)
      p += model.mass[size_t(i)] * sim.data().v[size_t(i)];
    return p;
  };
  const Vec3 start = momentum(left);
  double most_push = 0.0, deepest_node = 0.0;
  int most_solves = 0;
  for (int k = 0; k < 200; ++k) {
    sim.step();
    ASSERT_LT(implicit_residual_force(sim.data()), 1e-10) << "step " << k;
    most_solves = std::max(most_solves, implicit_iterations(sim.data()));
    most_push = std::max(most_push, sim.data().pair_contact_force[0].norm());
    deepest_node = std::max(deepest_node, deepest(sim.model(), sim.data().x).first);
    const Vec3 total = momentum(left) + momentum(right);
    ASSERT_LT((total - start).norm(), 1e-9 * start.norm()) << "step " << k;
  }
  std::printf("push up to %.3g N, at most %d solves a step, deepest %.3g m\n", most_push,
              most_solves, deepest_node);
  EXPECT_GT(most_push, 1e-3);
  EXPECT_LT(deepest_node, 1e-9);
  EXPECT_GT(momentum(right).x(), 0.5 * start.x());  // the right ball took most of it
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// A soft ball held by its far cap and a ball pressed 4 mm into it over 0.6 s: the pressing
// ball rigid and driven by the schedule (an instrument), or elastic with every node moved by
// it. In implicit steps of 5 ms (static: the implicit static solver to 1e-10 N).
Model pressed_ball(bool rigid, bool statics) {
  Model model;
  const MaterialSpec soft = testing::material(100.0);
  const int left = add_elastic_component(
      model, "left", make_ellipsoid_volume({0.01, 0.01, 0.01}, 2, 2, Vec3(-0.0102, 0, 0)), soft);
  const Mesh ball = make_ellipsoid_volume({0.01, 0.01, 0.01}, 2, 2, Vec3(0.0102, 0.002, 0));
  const Schedule push{{0.0, 0.6}, {Vec3::Zero(), Vec3(-0.004, 0, 0)}};
  int right = 0;
  if (rigid) {
    right = add_rigid_component(model, "right", ball, soft, true, push);
  } else {
    right = add_elastic_component(model, "right", ball, soft);
    add_prescribed_displacement(model,
                                {model.components[size_t(right)].nodes, {true, true, true}, push});
  }
  std::vector<int> cap;
  for (int i : model.components[size_t(left)].nodes)
    if (model.rest_position[size_t(i)].x() < -0.018) cap.push_back(i);
  add_fixed_nodes(model, cap);
  add_contact_pair(model, left, right);
  model.damping = 20.0;
  model.settings.integrator = Integrator::implicit;
  model.settings.implicit_tolerance = 1e-10;
  model.settings.implicit_iterations = 500;
  model.settings.dt = 5e-3;
  if (statics) {
    model.settings.mode = SolveMode::static_equilibrium;
    model.settings.solver = StaticSolver::implicit;
    model.settings.tolerance = 1e-10;
    model.settings.duration = 0.6;
  }
  finalize(model);
  return model;
}

// Pushed by implicit steps, then relaxed at the push's end by the implicit static solver (the
// static residual does not see a node inside the other ball: a contact acts in steps).
Simulator pressed_and_relaxed(bool rigid) {
  Simulator run(pressed_ball(rigid, false));
  int most = 0;
  while (run.data().time < 0.6 - 1e-12) {
    run.step();
    EXPECT_LE(implicit_residual_force(run.data()), 1e-10) << "t = " << run.data().time;
    most = std::max(most, implicit_iterations(run.data()));
  }
  Simulator sim(pressed_ball(rigid, true));
  sim.data() = run.data();
  const StaticResult r = sim.solve_static();
  EXPECT_TRUE(r.converged) << r.residual;
  std::printf("%s: at most %d solves a step, then %ld static steps\n",
              rigid ? "rigid" : "moved node by node", most, r.iterations);
  return sim;
}

// The pressing ball as a driven rigid object: the same equilibrium as the elastic ball moved
// node by node (to the tolerance's share of the push), no node inside the other ball, and the
// contact's push taken by the soft ball's held cap.
TEST(ImplicitPairs, ADrivenRigidBallPressesAsABallMovedNodeByNode) {
  const Simulator rigid = pressed_and_relaxed(true), moved = pressed_and_relaxed(false);
  const Vec3 push = rigid.data().pair_contact_force[0];
  const auto [depth, touching] = deepest(rigid.model(), rigid.data().x);
  double gap = 0.0, sag = 0.0;
  for (int i : rigid.model().components[0].nodes) {
    gap = std::max(gap, (rigid.data().x[size_t(i)] - moved.data().x[size_t(i)]).norm());
    sag =
        std::max(sag, (rigid.data().x[size_t(i)] - rigid.model().rest_position[size_t(i)]).norm());
  }
  std::printf(
      "rigid: push (%.9g %.9g %.9g) N, %d nodes touching; moved node by node: push "
      "(%.9g %.9g %.9g) N; soft ball %.3g m apart, displaced up to %.3g m\n",
      push.x(), push.y(), push.z(), touching, moved.data().pair_contact_force[0].x(),
      moved.data().pair_contact_force[0].y(), moved.data().pair_contact_force[0].z(), gap, sag);
  EXPECT_LT(push.x(), -0.01);  // the rigid ball pushes the soft one back
  EXPECT_LT(depth, 1e-9);
  EXPECT_GE(touching, 1);
  EXPECT_LT((held_by_supports(rigid, 0) + push).norm(), 1e-8);
  EXPECT_LT((moved.data().pair_contact_force[0] - push).norm(), 1e-8);
  EXPECT_LT(gap, 1e-6 * sag);
}

}  // namespace
}  // namespace phymul
