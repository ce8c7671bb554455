#include "compositor/gather.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "common/wire/pixels.h"
#include "compositor/over.h"

namespace tessera::compositor {
namespace {

using proto::FrameParams;
using proto::Piece;

FrameParams params(uint64_t frame, int bricks, uint32_t epoch = 0) {
  FrameParams p;
  p.frame = frame;
  p.epoch = epoch;
  p.width = 8;
  p.height = 4;
  p.format = proto::PixelFormat::RGBA32F;
  auto& work = p.work.emplace<proto::SortLastWork>();
  for (int b = 0; b < bricks; ++b) work.bricks.push_back({(uint32_t)b, {}});
  for (int b = 0; b < bricks; ++b) work.order.push_back(bricks - 1 - b);  // back bricks first in index order
  p.regions = {{0, {0, 0, 8, 4}, ""}};
  return p;
}

// A piece whose single pixel at (b, 0) has alpha 0.5 and colour b/10 (exact in float).
Piece piece(uint64_t frame, uint32_t brick, uint32_t epoch = 0) {
  Piece p;
  p.frame = frame;
  p.epoch = epoch;
  p.renderer = brick;
  p.brick = brick;
  p.region = {0, 0, 8, 4};
  p.active = {0, 0, 8, 4};
  p.format = proto::PixelFormat::RGBA32F;
  ImageF img(8, 4);
  for (int x = 0; x < 8; ++x) img.at(x, 0)[0] = 0.1f * (brick + 1), img.at(x, 0)[3] = 0.5f;
  p.pixels = packPixels(img, p.active, p.format);
  return p;
}

TEST(Gather, FrameIsReadyOnlyWithParamsAndEveryBrick) {
  Gather g(0);
  EXPECT_EQ(g.addPiece(piece(0, 0)), "");
  EXPECT_FALSE(g.pop());  // no parameters yet: pieces may arrive first
  EXPECT_EQ(g.addParams(params(0, 2)), "");
  EXPECT_FALSE(g.pop());
  EXPECT_EQ(g.addPiece(piece(0, 1)), "");
  auto r = g.pop();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->pieces.size(), 2u);
  ASSERT_TRUE(r->region);
  EXPECT_EQ(*r->region, (Rect{0, 0, 8, 4}));
}

// What the compositor's heartbeats say it awaits: in the oldest frame it waits on, the
// renderer of the first brick whose piece is not here (nothing before FrameParams).
TEST(Gather, SaysWhoseRenderersPieceItAwaits) {
  Gather g(0);
  EXPECT_EQ(g.addPiece(piece(0, 0)), "");
  EXPECT_FALSE(g.awaited()) << "no FrameParams yet";
  FrameParams p0 = params(0, 3);
  std::get<proto::SortLastWork>(p0.work).bricks[2].renderer = 7;
  EXPECT_EQ(g.addParams(p0), "");
  EXPECT_EQ(g.addParams(params(1, 3)), "");
  auto a = g.awaited();
  ASSERT_TRUE(a);
  EXPECT_EQ(*a, (std::pair<uint64_t, uint32_t>{0, 1}));
  EXPECT_EQ(g.addPiece(piece(0, 1)), "");
  a = g.awaited();
  ASSERT_TRUE(a);
  EXPECT_EQ(*a, (std::pair<uint64_t, uint32_t>{0, 7})) << "brick 2 is renderer 7's";
}

// A binary-swap frame has no regions (its renderers send their bands to the display): the
// compositor has nothing to wait for, and the frames after it are not held up.
TEST(Gather, ABinarySwapFrameIsNotOurs) {
  Gather g(0);
  FrameParams swap = params(0, 2);
  swap.regions.clear();
  for (uint32_t b = 0; b < 2; ++b) std::get<proto::SortLastWork>(swap.work).swap.push_back({b, "tcp://x:1"});
  EXPECT_EQ(g.addParams(swap), "");
  EXPECT_EQ(g.addPiece(piece(0, 0)), "piece for a binary-swap frame (its bands go to the display)");
  auto r = g.pop();
  ASSERT_TRUE(r);
  EXPECT_FALSE(r->region);
  EXPECT_TRUE(r->pieces.empty());
  EXPECT_EQ(g.addParams(params(1, 1)), "");
  EXPECT_EQ(g.addPiece(piece(1, 0)), "");
  r = g.pop();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->params.frame, 1u);
}

TEST(Gather, RejectsDuplicatesStrangersAndStaleEpochs) {
  Gather g(0);
  g.addParams(params(0, 2, 1));
  EXPECT_EQ(g.addPiece(piece(0, 0, 1)), "");
  EXPECT_NE(g.addPiece(piece(0, 0, 1)), "") << "duplicate brick";
  EXPECT_NE(g.addPiece(piece(0, 5, 1)), "") << "brick out of range";
  EXPECT_NE(g.addPiece(piece(0, 1, 0)), "") << "older epoch";
  Piece wrong_region = piece(0, 1, 1);
  wrong_region.region = {0, 0, 4, 4};
  wrong_region.active = {0, 0, 4, 4};
  wrong_region.pixels.resize(4 * 4 * 16);
  EXPECT_NE(g.addPiece(wrong_region), "") << "cut for another region";
  EXPECT_FALSE(g.pop());
}

TEST(Gather, CancelledFramesAreGivenUpAndTheirLatePartsQuietlyDiscarded) {
  Gather g(0);
  g.addParams(params(0, 2));
  g.addParams(params(1, 2));
  EXPECT_EQ(g.addPiece(piece(0, 0)), "");
  FrameParams moved = params(2, 2);
  moved.first_wanted = 2;  // the camera moved: frames 0 and 1 are stale
  EXPECT_EQ(g.addParams(moved), "");
  EXPECT_EQ(g.pending(), 1u) << "the cancelled frames are still held";
  EXPECT_EQ(g.addPiece(piece(0, 1)), "") << "a late part of a cancelled frame is not a fault";
  EXPECT_EQ(g.addPiece(piece(1, 0)), "");
  EXPECT_FALSE(g.pop()) << "a cancelled frame was completed";
  EXPECT_EQ(g.addPiece(piece(2, 0)), "");
  EXPECT_EQ(g.addPiece(piece(2, 1)), "");
  auto r = g.pop();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->params.frame, 2u);
  EXPECT_TRUE(g.takeLateDrops().empty());
  EXPECT_NE(g.addPiece(piece(2, 1)), "") << "a part of a finished frame is still a fault";
}

// A fast drag cancels again before the parts of the last cancel have all arrived.
TEST(Gather, PartsOfAnEarlierCancelAreStillDiscardedQuietlyAfterANewerOne) {
  Gather g(0);
  g.addParams(params(0, 2));
  for (uint64_t f = 1; f <= 2; ++f) {
    FrameParams moved = params(f, 2);
    moved.first_wanted = f;  // each cancels the frame before it
    EXPECT_EQ(g.addParams(moved), "");
  }
  EXPECT_EQ(g.addPiece(piece(0, 0)), "") << "a part of the first cancelled frame";
  EXPECT_EQ(g.addPiece(piece(1, 1)), "") << "a part of the second";
  EXPECT_TRUE(g.takeLateDrops().empty());
  EXPECT_EQ(g.addPiece(piece(2, 0)), "");
  EXPECT_EQ(g.addPiece(piece(2, 1)), "");
  auto r = g.pop();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->params.frame, 2u);
}

TEST(Gather, NewEpochReissuesFramesInFlight) {
  Gather g(0);
  g.addParams(params(0, 2, 0));
  g.addPiece(piece(0, 0, 0));
  // Membership changed: frame 0 comes again with one brick under epoch 1.
  EXPECT_EQ(g.addParams(params(0, 1, 1)), "");
  EXPECT_FALSE(g.pop()) << "the old epoch's piece must not complete the new frame";
  EXPECT_EQ(g.addPiece(piece(0, 0, 1)), "");
  auto r = g.pop();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->params.epoch, 1u);
}

// A stage came back right after its loss: epoch 2 re-issues frame 0 while epoch 1's issue
// is still arriving, and a renderer's epoch-2 piece overtakes the epoch-2 FrameParams (they
// travel on different sockets). The newer piece replaces the held one; the frame completes
// once, under epoch 2, with epoch 2's pieces only.
TEST(Gather, ANewerEpochsPieceBeforeItsParamsReplacesTheStaleOne) {
  Gather g(0);
  EXPECT_EQ(g.addParams(params(0, 2, 1)), "");
  EXPECT_EQ(g.addPiece(piece(0, 0, 1)), "");
  EXPECT_EQ(g.addPiece(piece(0, 0, 2)), "") << "not a duplicate: a newer epoch";
  EXPECT_NE(g.addPiece(piece(0, 0, 1)), "") << "the stale epoch's piece comes too late";
  EXPECT_EQ(g.addPiece(piece(0, 1, 1)), "");
  EXPECT_FALSE(g.pop()) << "epoch 1's FrameParams must not complete with an epoch-2 piece";
  EXPECT_EQ(g.addParams(params(0, 2, 2)), "");
  EXPECT_FALSE(g.pop()) << "epoch 1's brick 1 was stale";
  EXPECT_EQ(g.addPiece(piece(0, 1, 2)), "");
  auto r = g.pop();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->params.epoch, 2u);
  for (const auto& p : r->pieces) EXPECT_EQ(p.epoch, 2u);
  EXPECT_TRUE(g.takeLateDrops().empty());
}

// Compositing follows the master's visibility order, never arrival order: every arrival
// permutation gives the same, exactly known image.
TEST(Gather, ResultIsIndependentOfArrivalOrder) {
  std::vector<uint32_t> arrival = {0, 1, 2};
  std::vector<uint8_t> first;
  do {
    Gather g(0);
    g.addParams(params(3, 3));
    for (uint32_t b : arrival) ASSERT_EQ(g.addPiece(piece(3, b)), "");
    auto r = g.pop();
    ASSERT_TRUE(r);
    std::vector<float> row;
    Image8 out(8, 4);
    compositeRegion(*r->region, r->params.sortLast()->order, r->pieces, row, out);
    // Order 2,1,0 (front to back): c = .3*1 + .5*.2 + .25*.1 = .425; a = 1 - .5^3 = .875.
    EXPECT_EQ(out.at(0, 0)[0], (uint8_t)std::lround(0.425 * 255));
    EXPECT_EQ(out.at(0, 0)[3], (uint8_t)std::lround(0.875 * 255));
    if (first.empty()) first = out.px;
    EXPECT_EQ(out.px, first);
  } while (std::next_permutation(arrival.begin(), arrival.end()));
}

TEST(Gather, PendingFramesAreBounded) {
  const size_t one = piece(0, 0).pixels.size();
  Gather g(0, 10 * one);
  for (uint64_t f = 0; f < 3 * Gather::kAheadWithoutParams; ++f) g.addPiece(piece(f, 0));
  EXPECT_LE(g.waitingBytes(), 10 * one);
  EXPECT_LE(g.pending(), 10u);
}

// Defect: well-formed pieces for many future frames evicted the real pending frames.
TEST(Gather, FutureJunkNeverEvictsFramesWithParams) {
  Gather g(0);
  ASSERT_EQ(g.addParams(params(0, 2)), "");
  ASSERT_EQ(g.addPiece(piece(0, 0)), "");
  for (uint64_t f = 1; f <= 3 * Gather::kAheadWithoutParams; ++f) g.addPiece(piece(1000 + f, 0));
  ASSERT_EQ(g.addPiece(piece(0, 1)), "");
  auto r = g.pop();
  ASSERT_TRUE(r) << "the real frame was evicted";
  EXPECT_EQ(r->params.frame, 0u);
}

TEST(Gather, PartsWithoutParamsAreBoundedAheadOfNewestParams) {
  Gather g(0);
  ASSERT_EQ(g.addParams(params(5, 2)), "");
  EXPECT_EQ(g.addPiece(piece(6, 0)), "") << "a piece may beat its FrameParams";
  EXPECT_EQ(g.addPiece(piece(5 + Gather::kAheadWithoutParams, 0)), "");
  EXPECT_NE(g.addPiece(piece(6 + Gather::kAheadWithoutParams, 0)), "") << "too far ahead";
  EXPECT_NE(g.addPiece(piece(1000000, 0)), "");
  EXPECT_EQ(g.addParams(params(6, 2)), "");
  EXPECT_EQ(g.addPiece(piece(6, 1)), "");
  auto r = g.pop();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->params.frame, 6u);
}

TEST(Gather, PartsWithoutParamsAreBoundedByMembershipAndBytes) {
  const size_t one = piece(0, 0).pixels.size();
  Gather g(0, 3 * one);
  ASSERT_EQ(g.addParams(params(0, 2)), "");
  EXPECT_NE(g.addPiece(piece(1, 2)), "") << "brick beyond the newest FrameParams' bricks";
  EXPECT_NE(g.addPiece(piece(1, 7)), "");
  EXPECT_EQ(g.addPiece(piece(3, 0)), "");
  EXPECT_EQ(g.addPiece(piece(3, 1)), "");
  EXPECT_EQ(g.addPiece(piece(4, 0)), "");
  EXPECT_EQ(g.waitingBytes(), 3 * one);
  EXPECT_NE(g.addPiece(piece(5, 0)), "") << "over the byte budget";
  // A nearer frame makes room by evicting the farthest waiting parts (counted as drops).
  EXPECT_EQ(g.addPiece(piece(1, 0)), "");
  EXPECT_EQ(g.waitingBytes(), 3 * one);
  EXPECT_EQ(g.takeLateDrops().size(), 1u);
  // A newer epoch's parts may name bricks the known membership lacks: the budget bounds them.
  EXPECT_EQ(g.addPiece(piece(2, 5, 1)), "");
}

// Found by review: a part of an epoch whose FrameParams never come, sent for a frame that has
// older FrameParams, was held outside the budget (one per brick number, unbounded), and the
// frame it held back named nobody, so the master dropped this compositor.
TEST(Gather, NewerEpochPartsBesideOlderParamsAreBudgetedAndTheirSenderNamed) {
  const size_t one = piece(0, 0).pixels.size();
  Gather g(0, 3 * one);
  ASSERT_EQ(g.addParams(params(0, 2)), "");
  ASSERT_EQ(g.addPiece(piece(0, 0)), "");
  ASSERT_EQ(g.addPiece(piece(0, 1)), "");
  Piece stray = piece(0, 1, 5);
  stray.renderer = 1;
  EXPECT_EQ(g.addPiece(stray), "") << "it may have raced its FrameParams";
  EXPECT_EQ(g.waitingBytes(), one);
  EXPECT_FALSE(g.pop());
  ASSERT_TRUE(g.awaited());
  EXPECT_EQ(*g.awaited(), std::make_pair(uint64_t{0}, uint32_t{1})) << "the stray part's sender is named";
  int refused = 0;
  for (uint32_t b = 2; b < 50; ++b) refused += !g.addPiece(piece(0, b, 5)).empty();
  EXPECT_EQ(g.waitingBytes(), 3 * one) << "held within the budget";
  EXPECT_EQ(refused, 48 - 2);
}

}  // namespace
}  // namespace tessera::compositor
