// Rigid components: free fall, torque-free rotation against an independent integration of
// Euler's equations, driven motion, momentum of a rigid-elastic assembly.
#include "solver/rigid.hpp"

#include <gtest/gtest.h>

#include "phymul/simulation.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

Model rigid_box(const Vec3& size, const std::array<int, 3>& cells, bool driven = false,
                Schedule translation = {}, Schedule rotation = {}) {
  Model model;
  add_rigid_component(model, "bone", make_box(size, cells, CellType::hexa), testing::material(1.0),
                      driven, translation, rotation);
  return model;
}

TEST(RigidBody, MassAndInertiaFromTheNodeMasses) {
  Model model = rigid_box(Vec3(0.04, 0.02, 0.01), {4, 2, 1});
  finalize(model);
  const RigidBody& r = model.rigid_bodies[0];
  EXPECT_NEAR(r.mass, 1000.0 * 0.04 * 0.02 * 0.01, 1e-15);
  // Point masses: I_zz = sum m (x^2 + y^2), computed here directly in the rest frame.
  double izz = 0.0;
  for (int i = 0; i < model.node_count(); ++i)
    izz += model.mass[i] * (model.rest_position[i] - r.rest_center).head<2>().squaredNorm();
  EXPECT_NEAR(r.inertia.maxCoeff(), izz, 1e-12 * izz);  // z is the axis of largest moment
  for (int i = 0; i < model.node_count(); ++i) EXPECT_EQ(model.inverse_mass[i], Vec3::Zero());
}

TEST(RigidBody, FreeBodyFallsAsHalfGTSquared) {
  Model model = rigid_box(Vec3(0.02, 0.02, 0.02), {2, 2, 2});
  model.gravity = Vec3(0.0, 0.0, -9.81);
  model.settings.dt = 1e-4;
  finalize(model);
  Simulator sim(model);
  const Vec3 c0 = sim.data().bodies[0].center;
  // 0.15 s: 11 cm, within the stability guard's 10 model sizes.
  for (int k = 0; k < 1500; ++k) sim.step();
  const double t = sim.data().time;
  const double drop = c0.z() - sim.data().bodies[0].center.z();
  EXPECT_NEAR(drop, 0.5 * 9.81 * t * t, 1e-12);
  // Every node moved by the same amount, and the body did not turn.
  for (int i = 0; i < model.node_count(); ++i) {
    EXPECT_NEAR((sim.data().x[i] - model.rest_position[i] - Vec3(0, 0, -drop)).norm(), 0.0, 1e-12);
    EXPECT_NEAR(sim.data().v[i].z(), -9.81 * t, 1e-12);
  }
}

// Independent reference: Euler's equations in the principal frame and the quaternion
// kinematics, by classical Runge-Kutta with a step 50 times smaller.
struct Reference {
  Vec3 I;
  Vec3 w;                // body angular velocity
  Eigen::Quaterniond q;  // principal frame -> world
  void derivative(const Vec3& w_, const Eigen::Vector4d& q_, Vec3& dw, Eigen::Vector4d& dq) const {
    dw = Vec3((I[1] - I[2]) * w_[1] * w_[2] / I[0], (I[2] - I[0]) * w_[2] * w_[0] / I[1],
              (I[0] - I[1]) * w_[0] * w_[1] / I[2]);
    const Eigen::Quaterniond qq(q_[0], q_[1], q_[2], q_[3]);
    const Eigen::Quaterniond d = qq * Eigen::Quaterniond(0.0, w_[0], w_[1], w_[2]);
    dq = 0.5 * Eigen::Vector4d(d.w(), d.x(), d.y(), d.z());
  }
  void step(double h) {
    Eigen::Vector4d q4(q.w(), q.x(), q.y(), q.z());
    Vec3 k1w, k2w, k3w, k4w;
    Eigen::Vector4d k1q, k2q, k3q, k4q;
    derivative(w, q4, k1w, k1q);
    derivative(w + 0.5 * h * k1w, q4 + 0.5 * h * k1q, k2w, k2q);
    derivative(w + 0.5 * h * k2w, q4 + 0.5 * h * k2q, k3w, k3q);
    derivative(w + h * k3w, q4 + h * k3q, k4w, k4q);
    w += h / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
    q4 += h / 6.0 * (k1q + 2.0 * k2q + 2.0 * k3q + k4q);
    q = Eigen::Quaterniond(q4[0], q4[1], q4[2], q4[3]).normalized();
  }
};

TEST(RigidBody, TorqueFreeAsymmetricBodyKeepsAngularMomentumAndTumblesCorrectly) {
  Model model = rigid_box(Vec3(0.06, 0.03, 0.01), {6, 3, 1});  // three distinct moments
  model.settings.dt = 2e-4;
  finalize(model);
  Simulator sim(model);
  const RigidBody& r = sim.model().rigid_bodies[0];
  ASSERT_GT(r.inertia[1] - r.inertia[0], 0.1 * r.inertia[0]);
  ASSERT_GT(r.inertia[2] - r.inertia[1], 0.1 * r.inertia[1]);
  // Near the intermediate axis: the body flips over (Dzhanibekov), a demanding motion.
  const Vec3 w0(0.3, 20.0, 0.5);  // rad/s, principal frame
  RigidBodyState& body = sim.data().bodies[0];
  const Eigen::Matrix3d R0 = body.orientation.toRotationMatrix();
  body.angular_momentum = R0 * r.inertia.cwiseProduct(w0);
  place_rigid_nodes(sim.model(), sim.data());
  const Vec3 L0 = body.angular_momentum;
  const double energy0 = 0.5 * w0.dot(r.inertia.cwiseProduct(w0));
  EXPECT_NEAR(sim.kinetic_energy(), energy0, 1e-12 * energy0);  // nodes move with the body

  Reference ref{r.inertia, w0, body.orientation};
  double worst_energy = 0.0, worst_momentum = 0.0, lowest_w1 = w0[1];
  const int steps = 5000;  // 1 s: about three flips
  for (int k = 0; k < steps; ++k) {
    sim.step();
    for (int s = 0; s < 50; ++s) ref.step(model.settings.dt.value() / 50.0);
    lowest_w1 = std::min(lowest_w1, ref.w[1]);
    // Angular momentum from the nodes themselves, about the centre of mass.
    Vec3 L = Vec3::Zero();
    for (int i : r.nodes)
      L += sim.model().mass[i] *
           (sim.data().x[i] - sim.data().bodies[0].center).cross(sim.data().v[i]);
    worst_momentum = std::max(worst_momentum, (L - L0).norm() / L0.norm());
    worst_energy = std::max(worst_energy, std::abs(sim.kinetic_energy() / energy0 - 1.0));
  }
  // Measured: momentum 3e-15 (round-off), energy 1.2e-7 (bounded, O(h^2)), orientation
  // 7.5e-7 rad from the reference after three flips.
  EXPECT_LT(worst_momentum, 1e-12);
  EXPECT_LT(worst_energy, 1e-6);
  const Eigen::Quaterniond q = sim.data().bodies[0].orientation;
  const double angle = q.angularDistance(ref.q);
  EXPECT_LT(angle, 1e-5) << "reference w " << ref.w.transpose();
  // And it did flip: the spin about the intermediate axis reversed.
  EXPECT_LT(lowest_w1, -0.9 * w0[1]);
}

TEST(RigidBody, ConvergesToTheReferenceAtSecondOrder) {
  // The orientation error after 0.5 s for two step sizes: ratio about 4.
  auto error_with = [](double dt) {
    Model model = rigid_box(Vec3(0.06, 0.03, 0.01), {6, 3, 1});
    model.settings.dt = dt;
    finalize(model);
    Simulator sim(model);
    const RigidBody& r = sim.model().rigid_bodies[0];
    const Vec3 w0(2.0, 8.0, 3.0);
    RigidBodyState& body = sim.data().bodies[0];
    body.angular_momentum = body.orientation.toRotationMatrix() * r.inertia.cwiseProduct(w0);
    place_rigid_nodes(sim.model(), sim.data());
    Reference ref{r.inertia, w0, body.orientation};
    const int steps = int(std::lround(0.5 / dt));
    for (int k = 0; k < steps; ++k) sim.step();
    for (int k = 0; k < steps * 20; ++k) ref.step(dt / 20.0);
    return sim.data().bodies[0].orientation.angularDistance(ref.q);
  };
  const double coarse = error_with(2e-3), fine = error_with(1e-3);
  EXPECT_GT(coarse / fine, 3.5);
  EXPECT_LT(coarse / fine, 4.5);
}

TEST(RigidBody, DrivenBodyFollowsItsSchedules) {
  Schedule translation{{0.0, 1.0}, {Vec3::Zero(), Vec3(0.01, 0.0, -0.02)}};
  Schedule rotation{{0.0, 1.0}, {Vec3::Zero(), Vec3(0.0, 0.0, 0.5)}};
  Model model = rigid_box(Vec3(0.02, 0.01, 0.01), {2, 1, 1}, true, translation, rotation);
  model.gravity = Vec3(0.0, 0.0, -9.81);  // ignored: the driver holds it
  model.settings.dt = 1e-3;
  finalize(model);
  Simulator sim(model);
  for (int k = 0; k < 600; ++k) sim.step();
  const double t = sim.data().time;
  const Vec3 c0 = sim.model().rigid_bodies[0].rest_center;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.5 * t, Vec3::UnitZ()).toRotationMatrix();
  for (int i = 0; i < model.node_count(); ++i) {
    const Vec3 expected = c0 + Vec3(0.01, 0.0, -0.02) * t + R * (model.rest_position[i] - c0);
    EXPECT_NEAR((sim.data().x[i] - expected).norm(), 0.0, 1e-12);
  }
}

TEST(RigidBody, FreeRigidElasticAssemblyKeepsItsMomentum) {
  // A rigid plate and an elastic block sharing the plate's top face; random initial
  // velocities of the elastic nodes, no external force.
  Model model;
  add_rigid_component(
      model, "plate",
      make_box(Vec3(0.02, 0.02, 0.005), {2, 2, 1}, CellType::hexa, Vec3(0.0, 0.0, -0.0025)),
      testing::material(1.0));
  add_elastic_component(
      model, "block",
      make_box(Vec3(0.02, 0.02, 0.02), {2, 2, 2}, CellType::hexa, Vec3(0.0, 0.0, 0.01)),
      testing::material(50.0));
  const auto pairs =
      coincident_pairs(model, model.components[0].nodes, model.components[1].nodes, 1e-9);
  ASSERT_EQ(pairs.size(), 9u);
  stitch_nodes(model, pairs);
  finalize(model);
  model.settings.dt = 0.2 * stable_time_step(model);
  Simulator sim(model);
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1e-2);
  for (int i = 0; i < model.node_count(); ++i)
    if (sim.model().rigid_body_of[i] < 0) sim.data().v[i] = testing::random_vec3(n, rng);
  auto momentum = [&] {
    Vec3 p = sim.data().bodies[0].momentum;
    for (int i = 0; i < model.node_count(); ++i)
      if (sim.model().rigid_body_of[i] < 0) p += sim.model().mass[i] * sim.data().v[i];
    return p;
  };
  auto angular = [&] {
    const RigidBodyState& b = sim.data().bodies[0];
    Vec3 l = b.angular_momentum + b.center.cross(b.momentum);
    for (int i = 0; i < model.node_count(); ++i)
      if (sim.model().rigid_body_of[i] < 0)
        l += sim.model().mass[i] * sim.data().x[i].cross(sim.data().v[i]);
    return l;
  };
  const Vec3 p0 = momentum(), l0 = angular();
  double scale = 0.0;  // kg m/s
  for (int i = 0; i < model.node_count(); ++i)
    scale += sim.model().mass[i] * sim.data().v[i].norm();
  for (int k = 0; k < 2000; ++k) sim.step();
  // Round-off of 2000 steps of force sums, as for a free elastic body.
  EXPECT_LT((momentum() - p0).norm(), 1e-10 * scale);
  EXPECT_LT((angular() - l0).norm(), 1e-10 * scale * 0.02);
  // The node momentum of the rigid body agrees with the body's own.
  Vec3 nodes = Vec3::Zero();
  for (int i : sim.model().rigid_bodies[0].nodes) nodes += sim.model().mass[i] * sim.data().v[i];
  EXPECT_LT((nodes - sim.data().bodies[0].momentum).norm(), 1e-12 * scale);
}

TEST(RigidBody, DegenerateBodiesAreRefused) {
  Model model;
  add_rigid_component(model, "a", make_box(Vec3(0.01, 0.01, 0.01), {1, 1, 1}, CellType::hexa),
                      testing::material(1.0));
  add_rigid_component(
      model, "b", make_box(Vec3(0.01, 0.01, 0.01), {1, 1, 1}, CellType::hexa, Vec3(0.01, 0.0, 0.0)),
      testing::material(1.0));
  add_doubled_nodes(
      model, coincident_pairs(model, model.components[0].nodes, model.components[1].nodes, 1e-9));
  EXPECT_THROW(
      {
        try {
          finalize(model);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("two rigid components"), std::string::npos);
          throw;
        }
      },
      std::invalid_argument);
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// Static mode with a driven body: each load step starts from the body's new pose, and the
// elastic block doubled to it follows.
TEST(RigidBody, StaticLoadStepsMoveADrivenBody) {
  Model model;
  add_rigid_component(
      model, "plate",
      make_box(Vec3(0.02, 0.02, 0.005), {2, 2, 1}, CellType::hexa, Vec3(0.0, 0.0, 0.0225)),
      testing::material(1.0), true, Schedule{{0.0, 1.0}, {Vec3::Zero(), Vec3(0.0, 0.0, 0.002)}});
  const int block = add_elastic_component(
      model, "block",
      make_box(Vec3(0.02, 0.02, 0.02), {2, 2, 2}, CellType::hexa, Vec3(0.0, 0.0, 0.01)),
      testing::material(50.0));
  add_doubled_nodes(model, coincident_pairs(model, model.components[block].node_sets.at("top"),
                                            model.components[0].nodes, 1e-9));
  add_fixed_nodes(model, model.components[block].node_sets.at("bottom"));
  model.settings.mode = SolveMode::static_equilibrium;
  model.settings.load_steps = 2;
  model.settings.tolerance = 1e-9;
  finalize(model);
  Simulator sim(model);
  const StaticResult r = sim.solve_static();
  ASSERT_TRUE(r.converged);
  for (int i : sim.model().rigid_bodies[0].nodes)
    EXPECT_NEAR((sim.data().x[i] - model.rest_position[i] - Vec3(0, 0, 0.002)).norm(), 0.0, 1e-12);
  // The block is stretched: its mid-height nodes rose by about half the plate's move.
  double mid = 0.0;
  int count = 0;
  for (int i : model.components[block].nodes)
    if (std::abs(model.rest_position[i].z() - 0.01) < 1e-9)
      mid += sim.data().x[i].z() - model.rest_position[i].z(), ++count;
  mid /= count;
  EXPECT_GT(mid, 0.3 * 0.002);
  EXPECT_LT(mid, 0.7 * 0.002);
}

}  // namespace
}  // namespace phymul

namespace phymul {
namespace {

// A load on one corner of a free body: its momentum grows by F t exactly, its angular
// momentum by r x F t while the body has barely turned.
TEST(RigidBody, ALoadOnACornerGivesForceAndTorque) {
  Model model = rigid_box(Vec3(0.04, 0.02, 0.01), {2, 1, 1});
  const Vec3 F(0.0, 0.0, 1e-3);  // N
  add_applied_force(model, {{0}, Schedule::constant(F)});
  model.settings.dt = 1e-5;
  finalize(model);
  Simulator sim(model);
  const Vec3 r0 = model.rest_position[0] - sim.model().rigid_bodies[0].rest_center;
  for (int k = 0; k < 100; ++k) sim.step();
  const double t = sim.data().time;
  EXPECT_LT((sim.data().bodies[0].momentum - F * t).norm(), 1e-15 * F.norm());
  const Vec3 L = sim.data().bodies[0].angular_momentum;
  const Vec3 expected = r0.cross(F) * t;
  // The body turns by alpha t^2 / 2 ~ 1e-5 rad over the run, so the lever arm changes by
  // that little (measured: 5.6e-7 relative).
  EXPECT_LT((L - expected).norm(), 1e-5 * expected.norm());
  EXPECT_GT(L.dot(expected), 0.0);
}

}  // namespace
}  // namespace phymul
