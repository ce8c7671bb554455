#include "display/assembly.h"

#include <gtest/gtest.h>

#include "common/wire/swap_rule.h"

namespace tessera::display {
namespace {

using proto::FrameParams;
using proto::Strips;

FrameParams params(uint64_t frame, int compositors, uint32_t epoch = 0) {
  FrameParams p;
  p.frame = frame;
  p.epoch = epoch;
  p.width = 8;
  p.height = 4;
  for (int c = 0; c < compositors; ++c) p.regions.push_back({(uint32_t)c, {0, 2 * c, 8, 2}, ""});
  return p;
}

Strips strips(uint64_t frame, uint32_t compositor, uint32_t epoch = 0, size_t bytes = 16) {
  Strips s;
  s.frame = frame;
  s.epoch = epoch;
  s.sender = compositor;
  s.stream.assign(bytes, uint8_t(compositor + 1));
  return s;
}

// Strips as a compositor sends them (the inbox says who sent them: `role`).
std::string add(Assembly& a, Strips s, size_t bytes, proto::Role role = proto::Role::Compositor) {
  const uint32_t rank = s.sender;
  return a.addStrips({role, rank}, std::move(s), bytes);
}

TEST(Assembly, FramesAreShownInOrderOnlyWithParamsAndEveryRegion) {
  Assembly a(1 << 20);
  EXPECT_EQ(add(a, strips(0, 0), 100), "") << "strips may beat their FrameParams";
  EXPECT_FALSE(a.popNext());
  EXPECT_FALSE(a.nextHasParams());
  a.addParams(params(0, 2));
  a.addParams(params(1, 1));
  EXPECT_TRUE(a.nextHasParams());
  EXPECT_EQ(add(a, strips(1, 0), 50), "");
  EXPECT_FALSE(a.popNext()) << "frame 1 is complete but frame 0 is not: frames are shown in order";
  EXPECT_EQ(add(a, strips(0, 1), 100), "");
  auto f0 = a.popNext();
  ASSERT_TRUE(f0);
  EXPECT_EQ(f0->params->frame, 0u);
  EXPECT_EQ(f0->strips.size(), 2u);
  EXPECT_EQ(f0->bytes, 200u);
  auto f1 = a.popNext();
  ASSERT_TRUE(f1);
  EXPECT_EQ(f1->params->frame, 1u);
  EXPECT_FALSE(a.popNext());
  EXPECT_TRUE(a.takeLateDrops().empty());
}

// What the display's heartbeats say it awaits: the next frame's first sender without strips
// of its issue, only once its FrameParams are here.
TEST(Assembly, SaysWhoseStripsTheNextFrameAwaits) {
  Assembly a(1 << 20);
  EXPECT_FALSE(a.awaited());
  EXPECT_EQ(add(a, strips(0, 0, 1), 16), "");
  EXPECT_FALSE(a.awaited()) << "no FrameParams yet: the master's to send, not a sender's";
  a.addParams(params(0, 3, 1));
  a.addParams(params(1, 1, 1));
  auto w = a.awaited();
  ASSERT_TRUE(w);
  EXPECT_EQ(w->first, 0u);
  EXPECT_EQ(w->second.role, proto::Role::Compositor);
  EXPECT_EQ(w->second.rank, 1u) << "compositor 0's strips are here";
  EXPECT_EQ(add(a, strips(0, 1, 2), 16), "") << "a newer issue's strips, ahead of their FrameParams";
  w = a.awaited();
  ASSERT_TRUE(w);
  EXPECT_EQ(w->second.rank, 1u) << "compositor 1's strips are of another issue (epoch 2)";
  a.addParams(params(0, 3, 2));
  a.addParams(params(1, 1, 2));
  w = a.awaited();
  ASSERT_TRUE(w);
  EXPECT_EQ(w->second.rank, 0u) << "under epoch 2, compositor 0's strips (epoch 1) are not the frame's";
  EXPECT_EQ(add(a, strips(0, 0, 2), 16), "");
  EXPECT_EQ(add(a, strips(1, 0, 2), 16), "");
  w = a.awaited();
  ASSERT_TRUE(w);
  EXPECT_EQ(w->first, 0u) << "frame 1 is complete, frame 0 is shown first";
  EXPECT_EQ(w->second.rank, 2u);
  EXPECT_EQ(add(a, strips(0, 2, 2), 16), "");
  while (a.popNext()) {
  }
  EXPECT_FALSE(a.awaited()) << "nothing left to wait for";
}

TEST(Assembly, RejectsDuplicatesStrangersAndShownFramesQuietlySkipsStaleEpochs) {
  Assembly a(1 << 20);
  a.addParams(params(0, 2, 1));
  EXPECT_EQ(add(a, strips(0, 0, 1), 16), "");
  EXPECT_EQ(add(a, strips(0, 0, 1), 16), "duplicate strips");
  EXPECT_NE(add(a, strips(0, 5, 1), 16), "") << "no region of the frame";
  EXPECT_EQ(add(a, strips(0, 1, 0), 16), "") << "an older epoch: stale, not malformed";
  EXPECT_FALSE(a.popNext()) << "the stale strips completed the frame";
  EXPECT_EQ(add(a, strips(0, 1, 1), 16), "");
  ASSERT_TRUE(a.popNext());
  EXPECT_EQ(add(a, strips(0, 1, 1), 16), "strips for a frame already shown");
}

// A compositor came back right after its loss: epoch 2 re-issues frame 0 while epoch 1's
// issue is still arriving, and a compositor's epoch-2 strips overtake the epoch-2 FrameParams.
// The newer strips replace the held ones; the frame is shown once, under epoch 2, with epoch
// 2's strips only.
TEST(Assembly, ANewerEpochsStripsBeforeTheirParamsReplaceTheStaleOnes) {
  Assembly a(1 << 20);
  a.addParams(params(0, 2, 1));
  EXPECT_EQ(add(a, strips(0, 0, 1), 16), "");
  EXPECT_EQ(add(a, strips(0, 0, 2), 16), "") << "not a duplicate: a newer epoch";
  EXPECT_NE(add(a, strips(0, 0, 1), 16), "") << "the stale epoch's strips come too late";
  EXPECT_EQ(add(a, strips(0, 1, 1), 16), "");
  EXPECT_FALSE(a.popNext()) << "epoch 1's FrameParams must not complete with epoch-2 strips";
  a.addParams(params(0, 2, 2));
  EXPECT_FALSE(a.popNext()) << "epoch 1's strips of compositor 1 were stale";
  EXPECT_EQ(add(a, strips(0, 1, 2), 16), "");
  auto f = a.popNext();
  ASSERT_TRUE(f);
  EXPECT_EQ(f->params->epoch, 2u);
  for (const auto& [c, s] : f->strips) EXPECT_EQ(s.epoch, 2u);
  EXPECT_TRUE(a.takeLateDrops().empty());
}

TEST(Assembly, CancelledFramesAreSkippedAndTheirLateStripsQuietlyDiscarded) {
  Assembly a(1 << 20);
  a.addParams(params(0, 1));
  a.addParams(params(1, 1));
  FrameParams moved = params(2, 1);
  moved.first_wanted = 2;
  a.addParams(moved);
  EXPECT_EQ(add(a, strips(0, 0), 16), "");
  EXPECT_EQ(add(a, strips(1, 0), 16), "");
  EXPECT_FALSE(a.popNext());
  EXPECT_EQ(add(a, strips(2, 0), 16), "");
  auto f = a.popNext();
  ASSERT_TRUE(f);
  EXPECT_EQ(f->params->frame, 2u);
  EXPECT_TRUE(a.takeLateDrops().empty());
}

TEST(Assembly, StripsWithoutParamsAreBoundedAheadAndByBytes) {
  Assembly a(100);
  a.addParams(params(0, 1));
  EXPECT_NE(add(a, strips(Assembly::kAheadWithoutParams + 1, 0), 16), "") << "too far ahead";
  EXPECT_NE(add(a, strips(1, 3), 16), "") << "not a member of the newest FrameParams' epoch";
  EXPECT_EQ(add(a, strips(5, 0, 0, 60), 60), "");
  EXPECT_EQ(add(a, strips(2, 0, 0, 60), 60), "") << "a nearer frame evicts a farther one";
  const auto late = a.takeLateDrops();
  ASSERT_EQ(late.size(), 1u);
  EXPECT_NE(late[0].second.find("frame 5"), std::string::npos) << late[0].second;
  EXPECT_NE(add(a, strips(3, 0, 0, 60), 60), "") << "nothing farther to evict: over budget";
}

// A binary-swap frame has no regions: its renderers send their bands. Renderer 0 and
// compositor 0 are different senders; neither may stand in for the other.
TEST(Assembly, ABinarySwapFrameWaitsForItsRenderersBands) {
  Assembly a(1 << 20);
  FrameParams p = params(0, 0);
  auto& work = p.work.emplace<proto::SortLastWork>();
  for (uint32_t r = 0; r < 2; ++r) {
    work.bricks.push_back({r, {}});
    work.order.push_back((int)r);
    work.swap.push_back({r, "tcp://x:1"});
  }
  a.addParams(p);
  a.addParams(params(1, 1));  // a direct-send frame after it (a renderer was lost)
  using proto::Role;
  // Each strip lands only in its sender's part: the swap's bands (order 0, 1: renderer 0 in
  // front keeps the upper rows), a compositor's region.
  EXPECT_EQ(Assembly::areaOf(p, {Role::Renderer, 0}), (Rect{0, 0, 8, 2}));
  EXPECT_EQ(Assembly::areaOf(p, {Role::Renderer, 1}), (Rect{0, 2, 8, 2}));
  EXPECT_TRUE(Assembly::areaOf(p, {Role::Compositor, 0}).empty());
  EXPECT_EQ(Assembly::areaOf(params(1, 2), {Role::Compositor, 1}), (Rect{0, 2, 8, 2}));
  EXPECT_NE(add(a, strips(0, 0), 16), "") << "a compositor has no region in a binary-swap frame";
  EXPECT_EQ(add(a, strips(0, 0), 16, Role::Renderer), "");
  EXPECT_NE(add(a, strips(1, 0), 16, Role::Renderer), "") << "a renderer's strips in a direct-send frame";
  EXPECT_EQ(add(a, strips(1, 0), 16), "");
  EXPECT_FALSE(a.popNext()) << "renderer 1's band is missing";
  EXPECT_NE(add(a, strips(0, 2), 16, Role::Renderer), "") << "renderer 2 is not in the swap";
  EXPECT_EQ(add(a, strips(0, 1), 16, Role::Renderer), "");
  auto f0 = a.popNext();
  ASSERT_TRUE(f0);
  EXPECT_EQ(f0->strips.size(), 2u);
  for (const auto& [src, st] : f0->strips) EXPECT_EQ(src.role, Role::Renderer);
  ASSERT_TRUE(a.popNext());
}

// Three renderers swap in one round of three (proto::swapRadices): each finishes a third of
// the rows, by its place in the visibility order, and the frame is complete with the three
// bands. An image of fewer rows than bands: a renderer without rows is not waited for, and
// its strips are refused.
TEST(Assembly, ThreeRenderersFinishAThirdEachAndOneWithoutRowsIsNotWaitedFor) {
  using proto::Role;
  auto swapFrame = [](uint64_t frame, int height) {
    FrameParams p = params(frame, 0);
    p.height = height;
    auto& work = p.work.emplace<proto::SortLastWork>();
    for (uint32_t r = 0; r < 3; ++r) {
      work.bricks.push_back({r, {}});
      work.swap.push_back({r, "tcp://x:1"});
    }
    work.order = {2, 0, 1};  // places: renderer 2, 0, 1
    return p;
  };
  Assembly a(1 << 20);
  const FrameParams p = swapFrame(0, 6);
  a.addParams(p);
  EXPECT_EQ(Assembly::areaOf(p, {Role::Renderer, 2}), (Rect{0, 0, 8, 2})) << "place 0: the top third";
  EXPECT_EQ(Assembly::areaOf(p, {Role::Renderer, 0}), (Rect{0, 2, 8, 2}));
  EXPECT_EQ(Assembly::areaOf(p, {Role::Renderer, 1}), (Rect{0, 4, 8, 2}));
  EXPECT_EQ(add(a, strips(0, 2), 16, Role::Renderer), "");
  EXPECT_EQ(add(a, strips(0, 0), 16, Role::Renderer), "");
  EXPECT_FALSE(a.popNext()) << "renderer 1's band is missing";
  EXPECT_EQ(add(a, strips(0, 1), 16, Role::Renderer), "");
  auto f = a.popNext();
  ASSERT_TRUE(f);
  EXPECT_EQ(f->strips.size(), 3u);

  a.addParams(swapFrame(1, 2));  // two rows, three bands: place 0 keeps none (rows 0 * 2 / 3 to 1 * 2 / 3)
  EXPECT_TRUE(Assembly::areaOf(swapFrame(1, 2), {Role::Renderer, 2}).empty());
  EXPECT_NE(add(a, strips(1, 2), 16, Role::Renderer), "") << "a renderer without rows sends no band";
  EXPECT_EQ(add(a, strips(1, 0), 16, Role::Renderer), "");
  EXPECT_EQ(add(a, strips(1, 1), 16, Role::Renderer), "");
  auto two = a.popNext();
  ASSERT_TRUE(two) << "complete with the two bands that have rows";
  EXPECT_EQ(two->strips.size(), 2u);
}

// Frame 0 is complete under epoch 1 (direct send) while renderers' bands of its next issue
// (epoch 2, binary swap) wait for their FrameParams: it is shown without them, and only its
// own strips' bytes count.
TEST(Assembly, AFrameShowsOnlyTheStripsOfItsOwnIssue) {
  Assembly a(1 << 20);
  a.addParams(params(0, 1, 1));
  EXPECT_EQ(add(a, strips(0, 0, 2), 30, proto::Role::Renderer), "") << "a newer issue's strips may wait";
  EXPECT_EQ(add(a, strips(0, 0, 1), 16), "");
  auto f = a.popNext();
  ASSERT_TRUE(f);
  ASSERT_EQ(f->strips.size(), 1u);
  EXPECT_EQ(f->strips.begin()->first.role, proto::Role::Compositor);
  EXPECT_EQ(f->bytes, 16u);
  EXPECT_EQ(a.takeLateDrops().size(), 1u) << "the renderer's strips are counted as dropped";
}

}  // namespace
}  // namespace tessera::display
