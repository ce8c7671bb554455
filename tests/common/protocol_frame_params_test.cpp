// FrameParams on the wire: its cross-field invariants (order a permutation, regions and
// tiles inside the image, a known mode) are checked by the decoder, each failure named.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

#include "common/wire/protocol.h"
#include "tests/common/protocol_samples.h"

namespace tessera::proto {
namespace {

using namespace test;

TEST(Protocol, FramebufferAndTilesAreValidated) {
  Framebuffer fb = sampleFramebuffer();
  fb.pixels.pop_back();
  EXPECT_THROW(encode(fb, 1, Codec::None), std::invalid_argument);
  FrameParams p = sampleSortFirstParams();
  std::get<SortFirstWork>(p.work).tiles[1].tile = {630, 0, 20, 10};  // sticks out of the 640-wide image
  auto r = decodeFrameParams(encode(p, 1));
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("tile 1"), std::string::npos) << r.error();
}


TEST(Protocol, TruncatedPayloadWithResealedHeaderFailsOnTheField) {
  FrameParams p = sampleParams();
  p.work = SortFirstWork{};  // display_endpoint is then followed only by the mode and the 4-byte tile count
  Bytes m = encode(p, 1);
  m.resize(m.size() - 14);  // cuts into display_endpoint
  putLE(m, 24, m.size() - kHeaderSize, 4);  // raw_size == encoded_size for codec none
  reseal(m);
  auto r = decodeFrameParams(m);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("display_endpoint"), std::string::npos) << r.error();
}


TEST(Protocol, FrameParamsInvariantsAreChecked) {
  auto fails = [](FrameParams p, const std::string& word) {
    auto r = decodeFrameParams(encode(p, 1));
    ASSERT_FALSE(r) << "accepted: expected failure naming " << word;
    EXPECT_NE(r.error().find(word), std::string::npos) << r.error();
  };
  FrameParams p = sampleParams();
  auto work = [](FrameParams& q) -> SortLastWork& { return std::get<SortLastWork>(q.work); };
  { auto q = p; work(q).order = {0, 0, 1}; fails(q, "permutation"); }
  { auto q = p; work(q).order = {0, 1}; fails(q, "order"); }
  { auto q = p; work(q).order = {0, 1, 3}; fails(q, "permutation"); }
  { auto q = p; q.regions[1].region.h = 241; fails(q, "region 1"); }
  { auto q = p; work(q).bricks[1].brick.lo[2] = 256; fails(q, "brick 1"); }
  { auto q = p; q.width = 0; fails(q, "image"); }
  { auto q = p; q.height = 16385; fails(q, "image"); }
  { auto q = p; q.camera.fov = std::numeric_limits<double>::quiet_NaN(); fails(q, "camera.fov"); }
  { auto q = p; q.codec = Codec(9); fails(q, "codec"); }
}


// A swap plan: two renderers with one brick each, so both must be named once.
FrameParams swapParams() {
  FrameParams p = sampleParams();
  p.work = SortLastWork{{{0, {{0, 0, 0}, {128, 256, 256}}}, {1, {{128, 0, 0}, {256, 256, 256}}}},
                        {1, 0},
                        {{0, "ipc:///tmp/r0"}, {1, "tcp://10.0.0.2:5851"}}};
  p.regions.clear();  // the bands go to the display
  return p;
}

TEST(Protocol, SwapPlanRoundTripsAndIsValidated) {
  const FrameParams good = swapParams();
  auto ok = decodeFrameParams(encode(good, 1));
  ASSERT_TRUE(ok) << ok.error();
  EXPECT_EQ(*ok, good);
  auto refused = [](FrameParams p, const std::string& words) {
    auto r = decodeFrameParams(encode(p, 1));
    if (r) return ::testing::AssertionFailure() << "accepted";
    if (r.error().find(words) == std::string::npos) return ::testing::AssertionFailure() << r.error();
    return ::testing::AssertionSuccess();
  };
  FrameParams p = good;
  std::get<SortLastWork>(p.work).swap[1].renderer = 0;  // renderer 0 twice, renderer 1 never
  EXPECT_TRUE(refused(p, "swap names renderer 0"));
  p = good;
  std::get<SortLastWork>(p.work).swap[1].renderer = 7;  // owns no brick
  EXPECT_TRUE(refused(p, "swap names renderer 7"));
  p = good;
  std::get<SortLastWork>(p.work).swap[0].endpoint.clear();
  EXPECT_TRUE(refused(p, "endpoint of renderer 0 is empty"));
  p = good;
  std::get<SortLastWork>(p.work).swap.pop_back();  // one peer for two bricks
  EXPECT_TRUE(refused(p, "swap has 1 renderers for 2 bricks"));
  p = good;
  std::get<SortLastWork>(p.work).bricks[1].renderer = 0;  // one renderer, two bricks
  EXPECT_TRUE(refused(p, "more than one brick"));
  p = good;
  p.regions = sampleParams().regions;  // a compositor would wait for pieces no renderer sends
  EXPECT_TRUE(refused(p, "binary-swap frame with compositor regions"));
}

TEST(Protocol, UnknownFrameModeIsRefused) {
  FrameParams p = sampleParams();
  Bytes m = encode(p, 1);
  const std::string ep = p.display_endpoint;
  auto at = std::search(m.begin(), m.end(), ep.begin(), ep.end(), [](std::byte b, char c) { return b == std::byte(c); });
  ASSERT_NE(at, m.end());
  *(at + ep.size()) = std::byte{3};  // the mode byte follows display_endpoint
  reseal(m);
  auto r = decodeFrameParams(m);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("mode 3"), std::string::npos) << r.error();
}


}  // namespace
}  // namespace tessera::proto
