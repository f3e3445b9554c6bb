// The needle tests' scene (tests/constraints/needle_test.cpp,
// tests/solver/implicit_needle_test.cpp).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "constraints/needle.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "solver/implicit_step.hpp"

namespace phymul::testing {

// A 4 cm block (8^3 hexahedra, z from -2 to 2 cm), its base held unless `free`; a needle
// from 5 mm above its top going down at 1 cm/s to `depth` at `until`, then as `later` says.
// `integrator`: empty for the default (explicit, dt auto), else the simulation's extra keys.
struct BlockScene {
  double puncture = 0.2, friction = 20.0, cutting = 0.0;  // N, N/m, N
  double damping = 10.0;                                  // 1/s
  bool free = false;
  std::string depth = "[{t: 0 s, value: 0 mm}, {t: 3 s, value: 30 mm}]";
  std::string base = "[0.3 mm, 0.2 mm, 2.5 cm]";
  std::string direction = "[0, 0, -1]";
  std::string integrator = "dt: auto";
  // N: with implicit steps, the largest residual each step must end below (0: not checked).
  double converged = 0.0;

  std::string yaml() const {
    std::string s = "simulation: {" + integrator +
                    ", duration: 4 s, damping: " + std::to_string(damping) +
                    " 1/s}\n"
                    "objects:\n"
                    "  - name: block\n"
                    "    mesh: {generator: box, size: [4 cm, 4 cm, 4 cm], cells: [8, 8, 8]}\n"
                    "    material: {stiffness: 2000 N/m, density: 1000 kg/m^3}\n";
    if (!free) s += "constraints:\n  - {type: fixed, object: block, nodes: bottom}\n";
    s += "needles:\n  - name: biopsy\n    base: " + base + "\n    direction: " + direction +
         "\n    depth: " + depth + "\n    spacing: 1 mm\n    tissues:\n      - {object: block, " +
         "puncture_force: " + std::to_string(puncture) +
         " N, friction: " + std::to_string(friction) +
         " N/m, cutting_force: " + std::to_string(cutting) + " N}\n";
    return s;
  }
  Simulator simulator() const { return Simulator(compile_scene(parse_scene(yaml(), "n.yaml"))); }
  void step(Simulator& sim) const {
    sim.step();
    if (converged > 0.0) {
      EXPECT_LE(implicit_residual_force(sim.data()), converged) << "t = " << sim.data().time;
    }
  }
  void run_until(Simulator& sim, double t) const {
    while (sim.data().time < t - 1e-12) step(sim);
  }
};

inline const NeedleState& state(const Simulator& sim) { return sim.data().needles[0]; }
inline double axial(const Simulator& sim) {
  return needle_axial_force(sim.model().needles[0], state(sim));
}

inline void run_until(Simulator& sim, double t) {
  while (sim.data().time < t - 1e-12) sim.step();
}

// Inserted length L after puncture against the axial force. The tissue slides on the shaft,
// so every track point behind the cut (the newest point's cell, which takes the cutting
// force, zero here) carries its whole friction, friction x its length: F = friction x
// (L - the cut's length), the analytic law, within one spacing's share (the cut's length
// grows a spacing at a time) once the point last out of the cut slides. Never more than
// friction x L (to `slack`, N).
inline void expect_friction_law(BlockScene scene, double slack) {
  scene.puncture = 0.05;
  scene.friction = 5.0;
  Simulator sim = scene.simulator();
  while (state(sim).punctures.empty() && sim.data().time < 1.0) scene.step(sim);
  ASSERT_EQ(state(sim).punctures.size(), 1u);
  const double entry = state(sim).punctures[0].depth;
  double n = 0, sl = 0, sf = 0, sll = 0, slf = 0;
  const double share = scene.friction * 0.001;  // N, one spacing
  size_t points = 0;
  double made = 0.0;  // m, depth when the newest point was made
  while (sim.data().time < 2.5) {
    scene.step(sim);
    const double L = state(sim).depth - entry, F = axial(sim);
    EXPECT_LE(F, scene.friction * L + slack) << "L = " << L;
    if (state(sim).track.size() != points)
      points = state(sim).track.size(), made = state(sim).depth;
    // After the puncture's recoil, and 1 mm after the last point left the cut (it sticks
    // until the tissue's pull on it reaches its friction).
    if (L < 0.008 || state(sim).depth - made < 0.001) continue;
    const double behind = L - state(sim).track.back().length;
    EXPECT_NEAR(F, scene.friction * behind, share) << "L = " << L;
    n += 1, sl += behind, sf += F, sll += behind * behind, slf += behind * F;
  }
  const double slope = (n * slf - sl * sf) / (n * sll - sl * sl);
  EXPECT_NEAR(slope, scene.friction, 0.02 * scene.friction);
  EXPECT_GE(state(sim).track.size(), 3u);
}

// A tilted needle off the block's axis (lateral loads): every track point within `within` (m)
// of the axis.
inline void expect_track_on_shaft(BlockScene scene, double within) {
  scene.puncture = 0.05;
  scene.base = "[3 mm, -2 mm, 2.5 cm]";
  scene.direction = "[0.2, 0.1, -1]";
  Simulator sim = scene.simulator();
  scene.run_until(sim, 2.5);
  const Needle& n = sim.model().needles[0];
  ASSERT_GE(state(sim).track.size(), 3u);
  for (const TrackPoint& p : state(sim).track) {
    const Vec3 r = p.point.at(sim.data().x) - n.base;
    EXPECT_LT((r - r.dot(n.direction) * n.direction).norm(), within);
  }
  EXPECT_GT(needle_lateral_force(n, state(sim)), 1e-4);  // it did take lateral loads
}

// In to 20 mm and out again: the track is released, the tissue heals, and two seconds later
// every node is back at rest within 1e-3 of the largest displacement the insertion caused.
inline void expect_retraction_to_rest(BlockScene scene) {
  scene.puncture = 0.05;
  scene.depth = "[{t: 0 s, value: 0 mm}, {t: 2 s, value: 20 mm}, {t: 3 s, value: 0 mm}]";
  Simulator sim = scene.simulator();
  const Model& m = sim.model();
  auto largest_displacement = [&] {
    double d = 0.0;
    for (int i = 0; i < m.node_count(); ++i)
      d = std::max(d, (sim.data().x[i] - m.rest_position[i]).norm());
    return d;
  };
  scene.run_until(sim, 2.0);
  const double inserted = largest_displacement();
  EXPECT_GE(state(sim).track.size(), 2u);
  EXPECT_GT(inserted, 1e-3);
  scene.run_until(sim, 3.0);
  EXPECT_TRUE(state(sim).track.empty());
  EXPECT_EQ(state(sim).phase[0], needle_outside);
  scene.run_until(sim, 5.0);
  EXPECT_LT(largest_displacement(), 1e-3 * inserted);
  EXPECT_EQ(axial(sim), 0.0);
}

// Two organs in turn: a 2 cm slab over another, 1 mm apart, each held at its sides, each
// with its own puncture force (0.1 and 0.3 N). The needle presses and punctures the upper
// one, crosses it, then presses and punctures the lower one, each within `above` times its
// force. `simulation`: the integrator's keys.
inline void expect_two_tissues_crossed(const std::string& simulation, double above) {
  std::string yaml = "simulation: {" + simulation + ", duration: 3 s, damping: 10 1/s}\nobjects:\n";
  for (const char* slab : {"upper: 11", "lower: -10"}) {
    const std::string s = slab, name = s.substr(0, 5), z = s.substr(7);
    yaml += "  - name: " + name +
            "\n    mesh: {generator: box, size: [4 cm, 4 cm, 2 cm], cells: [8, 8, 4], center: "
            "[0, 0, " +
            z + " mm]}\n    material: {stiffness: 2000 N/m, density: 1000 kg/m^3}\n";
  }
  yaml += "constraints:\n";
  for (const char* name : {"upper", "lower"})
    for (const char* x : {"[-3 cm, -3 cm, -3 cm], max: [-1.9 cm, 3 cm, 3 cm]",
                          "[1.9 cm, -3 cm, -3 cm], max: [3 cm, 3 cm, 3 cm]"})
      yaml +=
          std::string("  - {type: fixed, object: ") + name + ", nodes: {box: {min: " + x + "}}}\n";
  yaml +=
      "needles:\n  - base: [0.3 mm, 0.2 mm, 26 mm]\n    direction: [0, 0, -1]\n"
      "    depth: [{t: 0 s, value: 0 mm}, {t: 3 s, value: 45 mm}]\n    tissues:\n"
      "      - {object: upper, puncture_force: 0.1 N, friction: 5 N/m}\n"
      "      - {object: lower, puncture_force: 0.3 N, friction: 5 N/m}\n";
  Simulator sim(compile_scene(parse_scene(yaml, "two.yaml")));
  run_until(sim, 3.0);
  const std::vector<PunctureEvent>& events = state(sim).punctures;
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].tissue, 0);
  EXPECT_EQ(events[1].tissue, 1);
  EXPECT_GT(events[0].force, 0.1);
  EXPECT_LT(events[0].force, 0.1 * above);
  EXPECT_GT(events[1].force, 0.3);
  EXPECT_LT(events[1].force, 0.3 * above);
  // The lower slab's surface is 26 mm down: met after the upper slab was crossed.
  EXPECT_GT(events[1].depth, 0.026);
  EXPECT_EQ(state(sim).phase[0], needle_punctured);
  EXPECT_EQ(state(sim).phase[1], needle_punctured);
  int in_upper = 0, in_lower = 0;
  for (const TrackPoint& p : state(sim).track) (p.tissue == 0 ? in_upper : in_lower) += 1;
  EXPECT_GE(in_upper, 2);
  EXPECT_GE(in_lower, 1);
}

// The force on the needle is minus the momentum it gives the tissue: a free block (no
// support, no damping, no gravity) gains the needle's impulses step by step, to within
// `within(scale, sim)` N s (scale: the impulses' sizes summed so far).
template <class Within>
void expect_momentum_is_the_needles_impulse(BlockScene scene, Within within) {
  scene.free = true;
  scene.damping = 0.0;
  scene.puncture = 0.0;  // through at once: the free block would ride on the tip
  scene.cutting = 0.01;
  Simulator sim = scene.simulator();
  const Model& m = sim.model();
  Vec3 impulse = Vec3::Zero();
  double scale = 0.0;
  while (sim.data().time < 1.5) {
    scene.step(sim);
    impulse -= state(sim).force * sim.data().dt;
    scale += state(sim).force.norm() * sim.data().dt;
    Vec3 momentum = Vec3::Zero();
    for (int i = 0; i < m.node_count(); ++i) momentum += m.mass[i] * sim.data().v[i];
    ASSERT_LT((momentum - impulse).norm(), within(scale, sim)) << sim.data().time;
  }
  EXPECT_EQ(state(sim).punctures.size(), 1u);
  EXPECT_GT(scale, 1e-3);
}

}  // namespace phymul::testing
