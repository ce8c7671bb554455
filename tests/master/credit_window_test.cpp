#include "master/credit_window.h"

#include <gtest/gtest.h>

namespace tessera::master {
namespace {

using namespace std::chrono_literals;
using Clock = CreditWindow::Clock;
using proto::Role;

const Clock::time_point kBegin = Clock::now();

TEST(CreditWindow, AtMostInFlightFrames) {
  CreditWindow w(2, {});
  EXPECT_TRUE(w.hasRoom());
  w.issue(0, 0, {}, {0}, {0}, kBegin);
  w.issue(1, 0, {}, {0}, {0}, kBegin);
  EXPECT_FALSE(w.hasRoom());
  EXPECT_FALSE(w.done(7, kBegin)) << "a frame not in flight";
  ASSERT_TRUE(w.done(0, kBegin + 40ms));
  EXPECT_TRUE(w.hasRoom());
  EXPECT_EQ(w.oldest(kBegin + 50ms)->first, 1u);
}

TEST(CreditWindow, DeadlineStartsGenerousThenFollowsTheMedian) {
  DeadlineOptions d{30, 2, 8};
  CreditWindow w(1, d);
  EXPECT_DOUBLE_EQ(w.deadlineMs(), 30000);
  for (int i = 0; i < 5; ++i) {
    w.issue(i, 0, {}, {0}, {0}, kBegin);
    w.done(i, kBegin + std::chrono::milliseconds(i == 4 ? 9000 : 100));  // one outlier
  }
  EXPECT_DOUBLE_EQ(w.typicalMs(), 100);
  EXPECT_DOUBLE_EQ(w.deadlineMs(), 2000) << "the floor";
  for (int i = 5; i < 40; ++i) {
    w.issue(i, 0, {}, {0}, {0}, kBegin);
    w.done(i, kBegin + 1s);
  }
  EXPECT_DOUBLE_EQ(w.deadlineMs(), 8000) << "k x median of the recent frames only";
}

TEST(CreditWindow, WaitingNamesRenderersThenCompositorsThenTheDisplay) {
  CreditWindow w(3, {});
  w.issue(5, 0, {}, {0, 1}, {0, 1}, kBegin);
  w.stats(Role::Renderer, 0, 5, 0);
  auto a = w.waiting(5);
  EXPECT_EQ(a.renderers, std::vector<uint32_t>{1});
  EXPECT_EQ(a.compositors, (std::vector<uint32_t>{0, 1}));
  EXPECT_FALSE(a.display);
  w.stats(Role::Renderer, 1, 5, 0);
  w.stats(Role::Compositor, 1, 5, 0);
  auto b = w.waiting(5);
  EXPECT_TRUE(b.renderers.empty());
  EXPECT_EQ(b.compositors, std::vector<uint32_t>{0});
  w.stats(Role::Compositor, 0, 5, 0);
  EXPECT_TRUE(w.waiting(5).display);
  // Issued again (new epoch): deliveries start over.
  w.issue(5, 1, {}, {0}, {0}, kBegin + 1s);
  EXPECT_EQ(w.waiting(5).renderers, std::vector<uint32_t>{0});
  EXPECT_DOUBLE_EQ(w.oldest(kBegin + 3s)->second, 2000);
  // Stats of the earlier issue (a stage that finished under the old roster) deliver nothing.
  w.stats(Role::Renderer, 0, 5, 0);
  EXPECT_EQ(w.waiting(5).renderers, std::vector<uint32_t>{0});
  w.stats(Role::Renderer, 0, 5, 1);
  EXPECT_TRUE(w.waiting(5).renderers.empty());
}

TEST(CreditWindow, CancelledFramesLeaveAtOnceAndOnlyFullFramesSetTheDeadline) {
  CreditWindow w(3, {30.0, 0.001, 1.0});
  FrameSpec full, quick;
  quick.interactive = true;
  w.issue(0, 0, full, {0}, {0}, kBegin);
  w.issue(1, 0, full, {0}, {0}, kBegin);
  w.issue(2, 0, quick, {0}, {0}, kBegin);
  EXPECT_FALSE(w.hasRoom());
  EXPECT_FALSE(w.hasRoom(5));
  EXPECT_EQ(w.cancelBelow(2), 2u);
  EXPECT_TRUE(w.hasRoom());
  EXPECT_FALSE(w.hasRoom(1)) << "interactive frames keep one in flight";
  EXPECT_FALSE(w.done(0, kBegin)) << "a cancelled frame is not in flight";
  auto d = w.done(2, kBegin + std::chrono::milliseconds(10));
  ASSERT_TRUE(d);
  EXPECT_TRUE(d->first.interactive);
  EXPECT_EQ(w.deadlineMs(), 30000) << "an interactive frame set the deadline";
}

}  // namespace
}  // namespace tessera::master
