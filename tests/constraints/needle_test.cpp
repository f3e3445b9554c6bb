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
  // Before contact the shape memory's roundoff alone moves the free block: 1e-13 N s is a
  // picometre per second on its mass, below any needle force here.
  testing::expect_momentum_is_the_needles_impulse(
      BlockScene{}, [](double scale, const Simulator&) { return 1e-9 * scale + 1e-13; });
}

// Two organs in turn: a 2 cm slab over another, 1 mm apart, each held at its sides, each
// with its own puncture force. The needle presses and punctures the upper one, crosses it,
// then presses and punctures the lower one at its force.
TEST(Needle, CrossesTwoTissuesInTurnEachAtItsOwnPunctureForce) {
  testing::expect_two_tissues_crossed("dt: auto", 1.02);
}

}  // namespace
}  // namespace phymul
