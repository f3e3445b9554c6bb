// Shared border nodes (Fig. 1a) by merging, and doubled nodes (Fig. 1b) by projection: the
// two ways of joining components, checked against each other.
#include <gtest/gtest.h>

#include <random>

#include "constraints/doubled.hpp"
#include "forces/shape_memory.hpp"
#include "phymul/forces.hpp"
#include "phymul/simulation.hpp"
#include "support/models.hpp"

namespace phymul {
namespace {

// Two blocks side by side along x, touching on the face x = 0 (5 x 5 coincident nodes).
Model two_blocks(double k_left = 40.0, double k_right = 10.0) {
  Model model;
  add_elastic_component(
      model, "left",
      make_box(Vec3(0.02, 0.02, 0.02), {4, 4, 4}, CellType::hexa, Vec3(-0.01, 0.0, 0.0)),
      testing::material(k_left));
  add_elastic_component(
      model, "right",
      make_box(Vec3(0.03, 0.02, 0.02), {6, 4, 4}, CellType::hexa, Vec3(0.015, 0.0, 0.0)),
      testing::material(k_right));
  return model;
}

std::vector<std::array<int, 2>> face_pairs(const Model& model) {
  return coincident_pairs(model, model.components[0].nodes, model.components[1].nodes, 1e-9);
}

TEST(Stitch, MergesCoincidentNodesAddingTheirMasses) {
  Model model = two_blocks();
  const auto pairs = face_pairs(model);
  ASSERT_EQ(pairs.size(), 25u);
  const int before = model.node_count();
  double total = 0.0;
  for (double m : model.mass) total += m;
  std::vector<double> pair_mass;
  for (const auto& [a, b] : pairs) pair_mass.push_back(model.mass[a] + model.mass[b]);
  stitch_nodes(model, pairs);
  finalize(model);
  EXPECT_EQ(model.node_count(), before - 25);
  double after = 0.0;
  for (double m : model.mass) after += m;
  EXPECT_NEAR(after, total, 1e-15);
  // A shared node is listed by both components and keeps the summed mass.
  for (size_t p = 0; p < pairs.size(); ++p) {
    const int shared = pairs[p][0];  // the left block's ids come first and do not move
    const auto& right = model.components[1].nodes;
    EXPECT_NE(std::find(right.begin(), right.end(), shared), right.end());
    EXPECT_NEAR(model.mass[shared], pair_mass[p], 1e-18);
  }
  // Each memory keeps its own neighbourhood: every neighbour of a node of the right
  // block's memory is a node of the right block.
  const auto& right = model.components[1].nodes;
  const ShapeMemory& m = model.shape_memory[1];
  for (int j : m.neighbours.indices)
    EXPECT_NE(std::find(right.begin(), right.end(), j), right.end());
}

TEST(Stitch, SharedNodeFeelsTheShapeMemoryOfBothComponents) {
  Model model = two_blocks();
  stitch_nodes(model, face_pairs(model));
  finalize(model);
  Data s = allocate_data(model);
  compute_forces(model, s, 0.0);
  for (const Vec3& f : s.f) EXPECT_LT(f.norm(), 1e-12);  // rest: no force
  // Move one shared node on the face centre: its force is the sum of both memories'
  // pulls, each component contributing in proportion to its stiffness.
  int centre = -1;
  for (int i : model.components[0].nodes)
    if ((model.rest_position[i] - Vec3::Zero()).norm() < 1e-12) centre = i;
  ASSERT_GE(centre, 0);
  s.x[centre] += Vec3(1e-4, 2e-5, -3e-5);
  compute_forces(model, s, 0.0);
  std::vector<Vec3> f_left(s.f.size(), Vec3::Zero()), f_right(s.f.size(), Vec3::Zero());
  std::vector<Eigen::Quaterniond> q(s.rotation.size(), Eigen::Quaterniond::Identity());
  const size_t n_left = model.shape_memory[0].nodes.size();
  std::vector<double> left = testing::block_scratch(model.shape_memory[0].plan),
                      right = testing::block_scratch(model.shape_memory[1].plan);
  add_shape_memory_forces(model.shape_memory[0], model.rest_position, s.x,
                          std::span(q.data(), n_left), f_left, left);
  add_shape_memory_forces(model.shape_memory[1], model.rest_position, s.x,
                          std::span(q.data() + n_left, q.size() - n_left), f_right, right);
  EXPECT_LT((s.f[centre] - f_left[centre] - f_right[centre]).norm(), 1e-15);
  // Both pull it back, and the stiffer block (K = 40 vs 10 N/m) pulls harder.
  const Vec3 d = Vec3(1e-4, 2e-5, -3e-5);
  EXPECT_LT(f_left[centre].dot(d), 0.0);
  EXPECT_LT(f_right[centre].dot(d), 0.0);
  EXPECT_GT(f_left[centre].norm(), 2.0 * f_right[centre].norm());
}

// Random velocities from a smooth field (coincident nodes share theirs), no net momentum.
void shake(Simulator& sim, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Matrix3d A;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) A(r, c) = n(rng);
  const Model& model = sim.model();
  Vec3 p = Vec3::Zero();
  double mass = 0.0;
  for (int i = 0; i < model.node_count(); ++i) {
    const Vec3& x = model.rest_position[i];
    sim.data().v[i] = 0.5 * A * x + 1e-3 * Vec3(std::sin(300 * x.x()), std::cos(200 * x.y()), 0);
    p += model.mass[i] * sim.data().v[i];
    mass += model.mass[i];
  }
  for (Vec3& v : sim.data().v) v -= p / mass;
}

Vec3 momentum(const Simulator& sim) {
  Vec3 p = Vec3::Zero();
  for (int i = 0; i < sim.model().node_count(); ++i) p += sim.model().mass[i] * sim.data().v[i];
  return p;
}

TEST(Stitch, FreeStitchedAssemblyKeepsItsMomentumWithTheReactionOption) {
  Model model = two_blocks();
  stitch_nodes(model, face_pairs(model));
  finalize(model);
  model.settings.dt = 0.3 * stable_time_step(model);
  Simulator sim(model);
  shake(sim, 5);
  const Vec3 p0 = momentum(sim);
  double scale = 0.0;
  for (int i = 0; i < model.node_count(); ++i) scale += model.mass[i] * sim.data().v[i].norm();
  for (int k = 0; k < 2000; ++k) sim.step();
  EXPECT_LT((momentum(sim) - p0).norm(), 1e-10 * scale);
}

TEST(Stitch, RefusesToMergeTwoNodesOfOneComponent) {
  Model model = two_blocks();
  // Nodes 0 and 1 of the left block are 5 mm apart: a tolerance that large pairs them.
  EXPECT_THROW(stitch_nodes(model, {{0, 1}}), std::invalid_argument);
  EXPECT_THROW(coincident_pairs(model, {0}, {1}, 0.0), std::invalid_argument);
}

// The paper's bladder and prostate: a surface organ with its volume kept, stitched to a
// volume organ through a limited number of nodes (here one, its lowest).
TEST(Stitch, SurfaceWithVolumeConstraintStitchedThroughOneNode) {
  Model model;
  add_elastic_component(model, "prostate",
                        make_box(Vec3(0.02, 0.02, 0.02), {2, 2, 2}, CellType::hexa),
                        testing::material(30.0));
  const int bladder = add_elastic_component(
      model, "bladder", make_ellipsoid_surface(Vec3(0.03, 0.03, 0.025), 2, Vec3(0, 0, 0.035)),
      testing::surface_material(500.0, 0.05, FrameMode::polar));
  add_volume_constraint(model, bladder);
  const double volume0 = model.volumes[0].target_volume;
  const auto pairs = coincident_pairs(model, model.components[1].node_sets.at("bottom"),
                                      model.components[0].nodes, 1e-9);
  ASSERT_EQ(pairs.size(), 1u);
  stitch_nodes(model, pairs);
  EXPECT_NEAR(model.volumes[0].target_volume, volume0, 1e-15);
  add_fixed_nodes(model, model.components[1].node_sets.at("top"));  // as in the paper
  model.gravity = Vec3(0.0, 0.0, -9.81);
  model.damping = 5.0;
  finalize(model);
  Simulator sim(model);
  const int shared = model.components[1].node_sets.at("bottom").front();
  for (int k = 0; k < 2000; ++k) sim.step();
  // The prostate hangs from the bladder through the shared node, which went down.
  EXPECT_LT(sim.data().x[shared].z(), model.rest_position[shared].z() - 1e-4);
  EXPECT_NEAR(sim.component_volumes()[1], volume0, 1e-10 * volume0);
}

TEST(Doubled, DoubledNodesCoincideAtEveryStepAndKeepMomentum) {
  Model model = two_blocks();
  add_doubled_nodes(model, face_pairs(model));
  finalize(model);
  model.settings.dt = 0.3 * stable_time_step(model);
  Simulator sim(model);
  shake(sim, 7);
  const Vec3 p0 = momentum(sim);
  double scale = 0.0;
  for (int i = 0; i < model.node_count(); ++i) scale += model.mass[i] * sim.data().v[i].norm();
  const auto pairs = sim.model().doubled_pairs;
  for (int k = 0; k < 2000; ++k) {
    sim.step();
    for (const auto& [a, b] : pairs) {
      ASSERT_EQ(sim.data().x[a], sim.data().x[b]) << "step " << k;
      ASSERT_EQ(sim.data().v[a], sim.data().v[b]) << "step " << k;
    }
  }
  EXPECT_LT((momentum(sim) - p0).norm(), 1e-10 * scale);
}

// Two nodes held together move as one node of their summed mass: the doubled assembly
// follows the stitched one (different code paths: projection against merging).
TEST(Doubled, MovesLikeTheStitchedAssembly) {
  for (const Integrator integrator : {Integrator::verlet, Integrator::newton_cotes}) {
    Model stitched = two_blocks(), doubled = two_blocks();
    const auto pairs = face_pairs(stitched);
    stitch_nodes(stitched, pairs);
    add_doubled_nodes(doubled, pairs);
    for (Model* m : {&stitched, &doubled}) {
      m->gravity = Vec3(0.0, 0.0, -9.81);
      m->damping = 2.0;
      m->settings.integrator = integrator;
      add_fixed_nodes(*m, m->components[0].node_sets.at("left"));
      finalize(*m);
    }
    const double dt = 0.3 * stable_time_step(doubled);
    stitched.settings.dt = doubled.settings.dt = dt;
    Simulator a(stitched), b(doubled);
    for (int k = 0; k < 1500; ++k) a.step(), b.step();
    // Node i of the stitched model is node i of the doubled one, or the partner it merged.
    double worst = 0.0, largest = 0.0;
    for (int c = 0; c < 2; ++c)
      for (size_t k = 0; k < stitched.components[c].nodes.size(); ++k) {
        const int i = a.model().components[c].nodes[k], j = b.model().components[c].nodes[k];
        worst = std::max(worst, (a.data().x[i] - b.data().x[j]).norm());
        largest = std::max(largest, (b.data().x[j] - doubled.rest_position[j]).norm());
      }
    EXPECT_GT(largest, 1e-3);  // it sagged by millimetres
    EXPECT_LT(worst, 1e-9 * largest) << (integrator == Integrator::verlet ? "verlet" : "nc");
  }
}

TEST(Doubled, AHeldMemberHoldsItsPartner) {
  Model model = two_blocks();
  const auto pairs = face_pairs(model);
  add_doubled_nodes(model, pairs);
  std::vector<int> held;
  for (const auto& p : pairs) held.push_back(p[0]);
  add_fixed_nodes(model, held);  // the left block's face only
  model.gravity = Vec3(0.0, 0.0, -9.81);
  finalize(model);
  model.settings.dt = 0.3 * stable_time_step(model);
  Simulator sim(model);
  for (int k = 0; k < 500; ++k) sim.step();
  for (const auto& [a, b] : pairs) {
    EXPECT_EQ(sim.data().x[a], model.rest_position[a]);
    EXPECT_EQ(sim.data().x[b], model.rest_position[a]);
  }
  // The right block hangs from the left one's face: it moved.
  EXPECT_GT((sim.data().x[model.components[1].nodes.back()] -
             model.rest_position[model.components[1].nodes.back()])
                .norm(),
            1e-4);
}

TEST(Doubled, GroupResidualIsTheSumOverItsMembers) {
  Model model = two_blocks();
  add_doubled_nodes(model, face_pairs(model));
  finalize(model);
  std::vector<Vec3> r(size_t(model.node_count()), Vec3::Zero());
  const auto [a, b] = model.doubled_pairs.front();
  r[a] = Vec3(1.0, 2.0, 3.0);
  r[b] = Vec3(-1.0, -2.0, -2.5);
  gather_doubled(model, r);
  EXPECT_EQ(r[std::min(a, b)], Vec3(0.0, 0.0, 0.5));
  EXPECT_EQ(r[std::max(a, b)], Vec3::Zero());
}

}  // namespace
}  // namespace phymul
