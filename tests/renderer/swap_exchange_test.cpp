// The renderer's binary-swap inbox (renderer/swap_exchange.h) over a real ZeroMQ socket:
// a partner's pieces wait for their round; malformed pieces and pieces that claim another
// renderer are dropped and counted, pieces of given-up frames are discarded quietly, the
// held pieces stay bounded (the farthest frames go first), and a round whose frame is no
// longer wanted ends at once; rounds advance as pieces come, never waiting.
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <thread>

#include "common/net/transport.h"
#include "common/wire/pixels.h"
#include "renderer/swap_exchange.h"

namespace tessera::renderer {
namespace {

const std::string kPartner = std::string(16, 'p') + "d";  // a data routing id, as StageLink makes them
const std::string kPartner8 = std::string(16, 'q') + "d";

proto::Piece piece(uint64_t frame, uint32_t epoch, uint32_t renderer, const Rect& region) {
  proto::Piece p;
  p.frame = frame;
  p.epoch = epoch;
  p.renderer = renderer;
  p.region = region;
  p.active = {region.x, region.y, 2, 2};
  p.format = proto::PixelFormat::RGBA16F;
  p.pixels.assign(2 * 2 * 8, std::byte{0});
  return p;
}

struct Rig {
  zmq::context_t ctx;
  DropCounter drops;
  SwapExchange ex{ctx, 1 << 20, 4096};
  zmq::socket_t partner{ctx, zmq::socket_type::dealer}, partner8{ctx, zmq::socket_type::dealer};
  Rig() {
    ex.bind("inproc://swap-exchange-test");
    ex.setRoster(proto::Roster{1, {{proto::Role::Renderer, 7, kPartner}, {proto::Role::Renderer, 8, kPartner8}}}, drops);
    partner.set(zmq::sockopt::routing_id, kPartner);
    partner.connect("inproc://swap-exchange-test");
    partner8.set(zmq::sockopt::routing_id, kPartner8);
    partner8.connect("inproc://swap-exchange-test");
  }
  void send(std::vector<std::byte> bytes) { partner.send(zmq::buffer(bytes.data(), bytes.size()), zmq::send_flags::none); }
  void send8(std::vector<std::byte> bytes) { partner8.send(zmq::buffer(bytes.data(), bytes.size()), zmq::send_flags::none); }
  // Receives until `n` messages were taken in (inproc delivers at once; bounded anyway).
  void settle() {
    for (int i = 0; i < 20; ++i) {
      ex.receive(drops);
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
};

// The rounds of frame p as the renderer plays them: advance() until they end, the socket
// polled (`idle`) while a partner's piece is awaited; nullopt when `idle` gives the frame up.
std::optional<Layer> playRounds(Rig& rig, const proto::FrameParams& p, const SwapPlan& plan, const ImageF& img,
                                const SwapExchange::Send& send, const std::function<bool(uint32_t)>& idle,
                                proto::StageStats& st) {
  rig.ex.start(p, 9, plan, img, {0, 0, img.width, img.height});
  while (const auto partner = rig.ex.advance(send, st, rig.drops)) {
    if (!idle(*partner)) {
      rig.ex.abandon();
      return std::nullopt;
    }
    rig.ex.receive(rig.drops);
  }
  return rig.ex.finish();
}

proto::FrameParams frameOf(uint64_t frame, uint32_t epoch, int w, int h) {
  proto::FrameParams p;
  p.frame = frame;
  p.epoch = epoch;
  p.width = w;
  p.height = h;
  p.format = proto::PixelFormat::RGBA16F;
  p.codec = Codec::None;
  return p;
}

TEST(SwapExchange, BadPiecesAreCountedStaleOnesDiscardedAndTheRightOneTaken) {
  Rig rig;
  const Rect keep{0, 0, 8, 4};
  auto bad = proto::encode(piece(5, 2, 7, keep), 7, Codec::Lzo);
  bad.back() ^= std::byte{0x5A};  // checksum no longer matches
  rig.send(bad);
  rig.send(proto::encode(piece(5, 2, 3, keep), 7, Codec::None));  // claims renderer 3
  rig.ex.setWanted(2, 5);
  rig.send(proto::encode(piece(4, 2, 7, keep), 7, Codec::None));  // cancelled frame: quiet
  rig.send(proto::encode(piece(5, 1, 7, keep), 7, Codec::None));  // older epoch: quiet
  rig.send(proto::encode(piece(6, 2, 7, keep), 7, Codec::None));  // the next frame: held
  rig.send(proto::encode(piece(5, 2, 7, keep), 7, Codec::None));  // the one this round needs
  rig.settle();
  EXPECT_EQ(rig.drops.total(), 2u);

  // A 2-renderer plan: this renderer (rank 9) is behind renderer 7, keeps the lower half.
  SwapPlan plan;
  plan.brick = 1;
  plan.rounds.push_back({keep, {{7, "inproc://nowhere", {0, 4, 8, 4}, -1}}});
  plan.band = keep;
  ImageF img(8, 8);
  std::vector<std::string> sent_to;
  auto send = [&](const std::string& endpoint, std::vector<std::byte>&&) { sent_to.push_back(endpoint); };
  int idles = 0;
  uint32_t awaited = 0;
  auto idle = [&](uint32_t partner) { return awaited = partner, ++idles < 5; };
  proto::StageStats st;
  auto band = playRounds(rig, frameOf(5, 2, 8, 8), plan, img, send, idle, st);
  ASSERT_TRUE(band);
  EXPECT_EQ(idles, 0) << "the piece was already there";
  EXPECT_EQ(sent_to, std::vector<std::string>{"inproc://nowhere"});
  EXPECT_EQ(band->rect, keep);
  // Frame 6's piece waited; frame 7 has none: its round ends when the frame is no longer wanted.
  EXPECT_TRUE(playRounds(rig, frameOf(6, 2, 8, 8), plan, img, send, idle, st));
  idles = 0;
  EXPECT_FALSE(playRounds(rig, frameOf(7, 2, 8, 8), plan, img, send, idle, st));
  EXPECT_FALSE(rig.ex.running());
  EXPECT_EQ(idles, 5);
  EXPECT_EQ(awaited, 7u) << "the heartbeats say whose piece is awaited";
  EXPECT_EQ(rig.drops.total(), 2u);
}

TEST(SwapExchange, HeldPiecesAreBoundedAndTheFarthestFramesGoFirst) {
  Rig rig;  // holds at most 4096 pixel bytes: 128 pieces of 32 bytes would not fit
  const Rect keep{0, 0, 8, 4};
  for (uint64_t f = 200; f > 10; --f) rig.send(proto::encode(piece(f, 1, 7, keep), 7, Codec::None));
  rig.settle();
  EXPECT_GT(rig.drops.total(), 0u) << "evictions are counted";
  // The nearest frame survived the evictions.
  SwapPlan plan;
  plan.rounds.push_back({keep, {{7, "x", {0, 4, 8, 4}, 1}}});
  plan.band = keep;
  ImageF img(8, 8);
  proto::StageStats st;
  auto none = [](const std::string&, std::vector<std::byte>&&) {};
  auto give_up = [](uint32_t) { return false; };
  EXPECT_TRUE(playRounds(rig, frameOf(11, 1, 8, 8), plan, img, none, give_up, st));
  EXPECT_FALSE(playRounds(rig, frameOf(200, 1, 8, 8), plan, img, none, give_up, st));
}

// The rounds as the renderer plays them while its next frame renders: advance() returns at
// once with the partner whose piece is awaited, sends each round's piece once however often
// it is called, and goes on from the round it stopped at when the piece comes (round 1 sends
// part of what round 0 blended); a frame given up leaves nothing running.
TEST(SwapExchange, RoundsResumeWhereTheyStoppedAndSendEachPieceOnce) {
  Rig rig;
  SwapPlan plan;
  plan.brick = 1;
  // Two rounds with renderer 7: keep the upper half, then the upper quarter (in front of 7).
  plan.rounds.push_back({{0, 0, 8, 4}, {{7, "inproc://round0", {0, 4, 8, 4}, -1}}});
  plan.rounds.push_back({{0, 0, 8, 2}, {{7, "inproc://round1", {0, 2, 8, 2}, -1}}});
  plan.band = {0, 0, 8, 2};
  ImageF img(8, 8);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) img.at(x, y)[3] = 0.5f;  // half transparent everywhere
  std::vector<std::string> sent_to;
  auto send = [&](const std::string& endpoint, std::vector<std::byte>&&) { sent_to.push_back(endpoint); };
  proto::StageStats st;
  rig.ex.setWanted(2, 8);
  rig.ex.start(frameOf(8, 2, 8, 8), 9, plan, img, {0, 0, 8, 8});
  ASSERT_TRUE(rig.ex.running());
  for (int i = 0; i < 3; ++i) EXPECT_EQ(rig.ex.advance(send, st, rig.drops), std::optional<uint32_t>(7));
  EXPECT_EQ(sent_to, std::vector<std::string>{"inproc://round0"}) << "round 0's piece leaves once";

  rig.send(proto::encode(piece(8, 2, 7, {0, 0, 8, 4}), 7, Codec::None));
  rig.settle();
  EXPECT_EQ(rig.ex.advance(send, st, rig.drops), std::optional<uint32_t>(7)) << "round 1 awaits its piece";
  EXPECT_EQ(rig.ex.advance(send, st, rig.drops), std::optional<uint32_t>(7));
  EXPECT_EQ(sent_to, (std::vector<std::string>{"inproc://round0", "inproc://round1"}));

  rig.send(proto::encode(piece(8, 2, 7, {0, 0, 8, 2}), 7, Codec::None));
  rig.settle();
  EXPECT_EQ(rig.ex.advance(send, st, rig.drops), std::nullopt);
  const Layer band = rig.ex.finish();
  EXPECT_FALSE(rig.ex.running());
  EXPECT_EQ(band.rect, (Rect{0, 0, 8, 2}));
  // The pieces were transparent: the band is this renderer's own pixels, blended twice.
  EXPECT_FLOAT_EQ(band.img.at(0, 0)[3], 0.5f);
  EXPECT_EQ(sent_to.size(), 2u);

  rig.ex.start(frameOf(9, 2, 8, 8), 9, plan, img, {0, 0, 8, 8});
  EXPECT_EQ(rig.ex.advance(send, st, rig.drops), std::optional<uint32_t>(7));
  rig.ex.abandon();
  EXPECT_FALSE(rig.ex.running());
  EXPECT_EQ(rig.drops.total(), 0u);
}

// A round of three (radix-k): this renderer is in front of renderers 7 and 8, in that order.
// 8's piece comes first and waits, since "over" may only join runs of bricks that are
// consecutive front to back; the round awaits 7, then blends 7's piece behind its own and
// 8's behind both. Blending 8's first would show it in front of 7.
TEST(SwapExchange, ARoundOfThreeBlendsEachPieceNextToTheRunBlendedSoFar) {
  Rig rig;
  SwapPlan plan;
  plan.brick = 0;
  const Rect keep{0, 0, 2, 1};
  plan.rounds.push_back({keep, {{7, "inproc://seven", {0, 1, 2, 1}, 1}, {8, "inproc://eight", {0, 2, 2, 1}, 2}}});
  plan.band = keep;
  ImageF img(2, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 2; ++x) img.at(x, y)[0] = 0.25f, img.at(x, y)[3] = 0.5f;  // red, half transparent
  auto uniform = [&](uint32_t from, float r, float g, float a) {
    ImageF px(2, 1);
    for (int x = 0; x < 2; ++x) px.at(x, 0)[0] = r, px.at(x, 0)[1] = g, px.at(x, 0)[3] = a;
    proto::Piece q = piece(3, 1, from, keep);
    q.active = keep;
    q.pixels = packPixels(px, {0, 0, 2, 1}, proto::PixelFormat::RGBA16F);
    return proto::encode(q, from, Codec::None);
  };
  std::vector<std::string> sent_to;
  auto send = [&](const std::string& endpoint, std::vector<std::byte>&&) { sent_to.push_back(endpoint); };
  proto::StageStats st;
  rig.ex.setWanted(1, 3);
  rig.ex.start(frameOf(3, 1, 2, 3), 9, plan, img, {0, 0, 2, 3});
  rig.send8(uniform(8, 0.0f, 1.0f, 1.0f));  // opaque green, the back
  rig.settle();
  EXPECT_EQ(rig.ex.advance(send, st, rig.drops), std::optional<uint32_t>(7)) << "8's piece waits for 7's";
  EXPECT_EQ(sent_to, (std::vector<std::string>{"inproc://seven", "inproc://eight"})) << "both pieces leave at once";
  rig.send(uniform(7, 0.5f, 0.0f, 0.5f));  // red, half transparent
  rig.settle();
  EXPECT_EQ(rig.ex.advance(send, st, rig.drops), std::nullopt);
  const Layer band = rig.ex.finish();
  ASSERT_EQ(band.rect, keep);
  // Front to back: own (0.25, 0, 0, 0.5), then 7's under 0.5 of light, then 8's under 0.25.
  EXPECT_FLOAT_EQ(band.img.at(1, 0)[0], 0.25f + 0.5f * 0.5f);
  EXPECT_FLOAT_EQ(band.img.at(1, 0)[1], 0.25f);
  EXPECT_FLOAT_EQ(band.img.at(1, 0)[3], 1.0f);

  // Mirrored: this renderer behind both, 8 in front of 7. 8's piece comes first and waits
  // for 7's; then 7 goes in front of this one's and 8 in front of both, and 8's opaque green
  // hides the rest. Blending 8's first would leave 7's red in front of it.
  plan.rounds[0] = {keep, {{8, "inproc://eight", {0, 1, 2, 1}, -2}, {7, "inproc://seven", {0, 2, 2, 1}, -1}}};
  auto at = [&](uint64_t frame, uint32_t from, float r, float g, float a) {
    std::vector<std::byte> bytes = uniform(from, r, g, a);
    auto q = proto::decodePiece(bytes);
    q->frame = frame;
    return proto::encode(*q, from, Codec::None);
  };
  rig.ex.setWanted(1, 4);
  rig.ex.start(frameOf(4, 1, 2, 3), 9, plan, img, {0, 0, 2, 3});
  rig.send8(at(4, 8, 0.0f, 1.0f, 1.0f));
  rig.settle();
  EXPECT_EQ(rig.ex.advance(send, st, rig.drops), std::optional<uint32_t>(7)) << "8's piece waits for 7's";
  rig.send(at(4, 7, 0.5f, 0.0f, 0.5f));
  rig.settle();
  EXPECT_EQ(rig.ex.advance(send, st, rig.drops), std::nullopt);
  const Layer behind = rig.ex.finish();
  EXPECT_FLOAT_EQ(behind.img.at(0, 0)[0], 0.0f);
  EXPECT_FLOAT_EQ(behind.img.at(0, 0)[1], 1.0f);
  EXPECT_EQ(rig.drops.total(), 0u);
}

// A round of many (a large prime count of renderers: k - 1 pieces a round) may hold more
// pieces than kMaxHeld: the bound grows with the roster's renderers.
TEST(SwapExchange, ALargeRosterMayHoldMorePieces) {
  Rig rig;
  proto::Roster roster{2, {{proto::Role::Renderer, 7, kPartner}, {proto::Role::Renderer, 8, kPartner8}}};
  for (uint32_t r = 20; r < 50; ++r) roster.members.push_back({proto::Role::Renderer, r, std::string(16, (char)('A' + r - 20)) + "d"});
  rig.ex.setRoster(roster, rig.drops);
  const Rect keep{0, 0, 8, 4};
  for (uint64_t f = 11; f < 111; ++f)  // 100 pieces of 32 bytes: within the byte bound, over kMaxHeld
    rig.send(proto::encode(piece(f, 1, 7, keep), 7, Codec::None));
  rig.settle();
  EXPECT_EQ(rig.drops.total(), 0u) << "nothing evicted";
}

}  // namespace
}  // namespace tessera::renderer
