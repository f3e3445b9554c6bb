// Needle insertion (constraints/needle.hpp): puncture at the tissue's force, friction along
// the shaft linear in the inserted length, the track on the shaft, retraction, momentum.
#include "constraints/needle.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "support/needle_scene.hpp"

namespace phymul {
namespace {

using testing::axial;
using testing::BlockScene;
using testing::run_until;
using testing::state;

TEST(Needle, PuncturesWhenThePushReachesThePunctureForce) {
  for (const double puncture : {0.1, 0.2}) {
    BlockScene scene;
    scene.puncture = puncture;
    Simulator sim = scene.simulator();
    double before = 0.0, touched_at = -1.0;
    while (state(sim).punctures.empty() && sim.data().time < 3.0) {
      before = std::max(before, axial(sim));
      sim.step();
      if (touched_at < 0.0 && state(sim).phase[0] == needle_pressed) touched_at = state(sim).depth;
    }
    ASSERT_EQ(state(sim).punctures.size(), 1u) << puncture;
    const PunctureEvent& e = state(sim).punctures[0];
    // The tip met the surface 5 mm down and pressed it in before it broke through.
    EXPECT_NEAR(touched_at, 0.005, 2e-5);
    EXPECT_GT(e.depth - touched_at, 0.001);
    // The push never exceeded the puncture force before, and broke through just above it
    // (one step's growth of the push).
    EXPECT_LE(before, puncture);
    EXPECT_GT(e.force, puncture);
    EXPECT_LT(e.force, puncture * 1.02);
    EXPECT_EQ(state(sim).phase[0], needle_punctured);
  }
}

// F = friction x (L - the cut's length) (testing::expect_friction_law).
TEST(Needle, AxialForceGrowsWithTheInsertedLengthAtTheFrictionPerLength) {
  testing::expect_friction_law(BlockScene{}, 1e-12);
}

TEST(Needle, TrackPointsStayOnTheShaft) {
  testing::expect_track_on_shaft(BlockScene{}, 1e-6);  // 1/500 of the radius
}

TEST(Needle, RetractionReleasesTheTrackAndTheTissueRelaxesToRest) {
  testing::expect_retraction_to_rest(BlockScene{});
}

// The force on the needle is minus the momentum it gives the tissue: a free block (no
// support, no damping, no gravity) gains exactly the needle's impulses, step by step.
TEST(Needle, TheForceOnTheNeedleIsMinusTheForceOnTheTissue) {
  BlockScene scene;
  scene.free = true;
  scene.damping = 0.0;
  scene.puncture = 0.0;  // through at once: the free block would ride on the tip
  scene.cutting = 0.01;
  Simulator sim = scene.simulator();
  const Model& m = sim.model();
  Vec3 impulse = Vec3::Zero();
  double scale = 0.0;
  while (sim.data().time < 1.5) {
    sim.step();
    impulse -= state(sim).force * sim.data().dt;
    scale += state(sim).force.norm() * sim.data().dt;
    Vec3 momentum = Vec3::Zero();
    for (int i = 0; i < m.node_count(); ++i) momentum += m.mass[i] * sim.data().v[i];
    // Before contact the shape memory's roundoff alone moves the free block: 1e-13 N s is a
    // picometre per second on its mass, below any needle force here.
    ASSERT_LT((momentum - impulse).norm(), 1e-9 * scale + 1e-13) << sim.data().time;
  }
  EXPECT_EQ(state(sim).punctures.size(), 1u);
  EXPECT_GT(scale, 1e-3);
}

// Two organs in turn: a 2 cm slab over another, 1 mm apart, each held at its sides, each
// with its own puncture force. The needle presses and punctures the upper one, crosses it,
// then presses and punctures the lower one at its force.
TEST(Needle, CrossesTwoTissuesInTurnEachAtItsOwnPunctureForce) {
  std::string yaml = "simulation: {dt: auto, duration: 3 s, damping: 10 1/s}\nobjects:\n";
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
  EXPECT_LT(events[0].force, 0.1 * 1.02);
  EXPECT_GT(events[1].force, 0.3);
  EXPECT_LT(events[1].force, 0.3 * 1.02);
  // The lower slab's surface is 26 mm down: met after the upper slab was crossed.
  EXPECT_GT(events[1].depth, 0.026);
  EXPECT_EQ(state(sim).phase[0], needle_punctured);
  EXPECT_EQ(state(sim).phase[1], needle_punctured);
  int in_upper = 0, in_lower = 0;
  for (const TrackPoint& p : state(sim).track) (p.tissue == 0 ? in_upper : in_lower) += 1;
  EXPECT_GE(in_upper, 2);
  EXPECT_GE(in_lower, 1);
}

}  // namespace
}  // namespace phymul
