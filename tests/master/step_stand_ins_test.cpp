// Which steps the farm asks for in place of a step that mixed a frame (master/step_stand_ins.h).
#include <gtest/gtest.h>

#include "master/step_stand_ins.h"

namespace tessera::master {
namespace {

TEST(StepStandIns, OnlyAFrameThatMixedTheAskedStepMakesAStandIn) {
  StepStandIns s;
  EXPECT_FALSE(s.frameShown(3, {2}));     // every renderer failed 3: asked again next time (its file may appear)
  EXPECT_FALSE(s.frameShown(4, {4}));     // a good step
  EXPECT_FALSE(s.frameShown(5, {3, 4}));  // nobody showed 5: not a mix of 5 with a stand-in
  EXPECT_EQ(s.stepFor(3), 3);
  EXPECT_TRUE(s.frameShown(3, {2, 3}));
  EXPECT_FALSE(s.frameShown(3, {1, 3})) << "the first stand-in stays";
  EXPECT_EQ(s.stepFor(3), 2);
  EXPECT_EQ(s.stepFor(4), 4);
}

TEST(StepStandIns, AStandInThatMixedInTurnIsFollowedAndCyclesEnd) {
  StepStandIns s;
  ASSERT_TRUE(s.frameShown(3, {2, 3}));
  ASSERT_TRUE(s.frameShown(2, {1, 2}));
  EXPECT_EQ(s.stepFor(3), 1);
  FrameSpec spec;
  spec.step = 3, spec.next_step = 2;
  const FrameSpec sent = s.sent(spec);
  EXPECT_EQ(sent.step, 1);
  EXPECT_EQ(sent.next_step, 1);
  ASSERT_TRUE(s.frameShown(1, {1, 3}));  // a cycle 3 -> 2 -> 1 -> 3: bounded, not a hang
  const int step = s.stepFor(3);
  EXPECT_TRUE(step == 1 || step == 2 || step == 3) << step;
}

}  // namespace
}  // namespace tessera::master
