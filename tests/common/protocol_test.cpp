// Wire protocol: every message round-trips, and every kind of damage is a clean failure
// with a reason (never a crash, never a partially trusted message).
#include "common/wire/protocol.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace tessera::proto {
namespace {

using Bytes = std::vector<std::byte>;

FrameParams sampleParams() {
  FrameParams p;
  p.frame = 42;
  p.epoch = 3;
  p.camera.eye = {1.5, -2, 3.25};
  p.camera.fov = 45;
  p.quality = {QualityName::Fast, 1.0 / 128, 0.95, true, false};
  p.width = 640;
  p.height = 480;
  p.codec = Codec::Lz4;
  p.format = PixelFormat::RGBA16F;
  p.regions = {{0, {0, 0, 640, 240}, "ipc:///tmp/c0"}, {1, {0, 240, 640, 240}, "tcp://127.0.0.1:5601"}};
  p.display_endpoint = "ipc:///tmp/display";
  p.work = SortLastWork{{{0, {{0, 0, 0}, {128, 256, 256}}}, {1, {{128, 0, 0}, {256, 256, 256}}}, {1, {{0, 0, 0}, {1, 1, 1}}}},
                        {2, 0, 1}};
  return p;
}

FrameParams sampleSortFirstParams() {
  FrameParams p = sampleParams();
  p.work = SortFirstWork{{{0, 1, {0, 0, 320, 240}}, {1, 0, {320, 0, 320, 1}}}};
  return p;
}

Framebuffer sampleFramebuffer() {
  Framebuffer f;
  f.frame = 5;
  f.epoch = 2;
  f.renderer = 1;
  f.width = 13;
  f.height = 7;
  f.pixels.resize(13 * 7 * 4);
  for (size_t i = 0; i < f.pixels.size(); ++i) f.pixels[i] = std::byte(uint8_t(i % 11 == 0 ? i : 0));
  f.render_ms = 2.5;
  return f;
}

Piece samplePiece(PixelFormat f) {
  Piece p;
  p.frame = 7;
  p.epoch = 3;
  p.renderer = 3;
  p.brick = 2;
  p.region = {0, 100, 64, 32};
  p.active = {10, 105, 20, 9};
  p.format = f;
  p.pixels.resize(size_t(p.active.area()) * bytesPerPixel(f));
  for (size_t i = 0; i < p.pixels.size(); ++i) p.pixels[i] = std::byte(uint8_t(i * 7 / 5));
  p.render_ms = 12.5;
  p.encode_ms = 0.25;
  return p;
}

Strips sampleStrips() {
  Strips s;
  s.frame = 9;
  s.epoch = 3;
  s.render_ms = 4.5;
  s.compositor = 1;
  s.stream.assign(1000, 0);
  for (size_t i = 0; i < 300; ++i) s.stream[i] = uint8_t(i);
  s.composite_ms = 3;
  s.encode_ms = 1;
  s.active_pixels = 123456789012ull;
  return s;
}

// Independent Adler-32 so the test checks the wire format rather than trusting the code.
uint32_t adler(std::span<const std::byte> p) {
  uint32_t a = 1, b = 0;
  for (std::byte x : p) {
    a = (a + uint8_t(x)) % 65521;
    b = (b + a) % 65521;
  }
  return (b << 16) | a;
}
void putLE(Bytes& m, size_t off, uint64_t v, int n) {
  for (int i = 0; i < n; ++i) m[off + i] = std::byte(uint8_t(v >> (8 * i)));
}
// Re-signs a (possibly edited) message so only the field under test is wrong.
void reseal(Bytes& m) {
  putLE(m, 28, m.size() - kHeaderSize, 4);
  putLE(m, 32, adler(std::span(m).subspan(kHeaderSize)), 4);
}

TEST(Protocol, HeaderLayoutOnTheWire) {
  Bytes m = encode(Welcome{Role::Compositor, 5}, 77);
  ASSERT_EQ(m.size(), kHeaderSize + 5);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(m.data()), 4), "TSER");
  EXPECT_EQ(uint8_t(m[4]), kVersion);
  EXPECT_EQ(uint8_t(m[6]), uint8_t(Type::Welcome));
  EXPECT_EQ(uint8_t(m[16]), 77);  // sender after the u64 frame
  auto h = decodeHeader(m);
  ASSERT_TRUE(h) << h.error();
  EXPECT_EQ(h->type, Type::Welcome);
  EXPECT_EQ(h->sender, 77u);
  EXPECT_EQ(h->codec, Codec::None);
  EXPECT_EQ(h->raw_size, 5u);
  EXPECT_EQ(h->encoded_size, 5u);
  EXPECT_EQ(h->checksum, adler(std::span(m).subspan(kHeaderSize)));
}

template <class T, class Dec>
void expectRoundTrip(const T& v, const Bytes& m, Dec dec, Type type) {
  auto h = decodeHeader(m);
  ASSERT_TRUE(h) << h.error();
  EXPECT_EQ(h->type, type);
  EXPECT_EQ(h->sender, 11u);
  auto back = dec(m);
  ASSERT_TRUE(back) << typeName(type) << ": " << back.error();
  EXPECT_TRUE(*back == v) << typeName(type);
}

TEST(Protocol, EveryStructuredMessageRoundTrips) {
  Hello hello{Role::Compositor, 4242, "tcp://127.0.0.1:7000"};
  expectRoundTrip(hello, encode(hello, 11), decodeHello, Type::Hello);
  expectRoundTrip(Welcome{Role::Display, 3}, encode(Welcome{Role::Display, 3}, 11), decodeWelcome, Type::Welcome);
  expectRoundTrip(Heartbeat{Role::Renderer, 9}, encode(Heartbeat{Role::Renderer, 9}, 11), decodeHeartbeat, Type::Heartbeat);
  expectRoundTrip(Probe{}, encode(Probe{}, 11), decodeProbe, Type::Probe);
  EXPECT_EQ(encode(Probe{}, 11).size(), kHeaderSize) << "Probe carries no payload";
  expectRoundTrip(Shutdown{"master exiting"}, encode(Shutdown{"master exiting"}, 11), decodeShutdown, Type::Shutdown);
  Roster roster{7, {{Role::Renderer, 0, std::string(16, '\x5a') + "d"}, {Role::Compositor, 3, "x"}}};
  expectRoundTrip(roster, encode(roster, 11), decodeRoster, Type::Roster);
  for (const FrameParams& fp : {sampleParams(), sampleSortFirstParams()}) {
    expectRoundTrip(fp, encode(fp, 11), decodeFrameParams, Type::FrameParams);
    EXPECT_EQ(decodeFrameParams(encode(fp, 11))->mode(), fp.mode());
  }
  StageStats st{Role::Compositor, 2, 99, 4.5, 1.25, 0.75, 4000000, 700000, 12345, {1, 2, 300, 400}, 6, {1.5, 0.25}, 7, 3, 99};
  expectRoundTrip(st, encode(st, 11), decodeStageStats, Type::Stats);
  FrameDone fd{1000, 16.5, 2.25, 888888, 3, 1};
  expectRoundTrip(fd, encode(fd, 11), decodeFrameDone, Type::FrameDone);
  Input in{-5.5, 10, 0.9, QualityName::Reference};
  expectRoundTrip(in, encode(in, 11), decodeInput, Type::Input);
  EXPECT_EQ(decodeHeader(encode(sampleParams(), 11))->frame, 42u) << "FrameParams::frame travels in the header";
}

TEST(Protocol, PixelMessagesRoundTripWithEveryCodecAndFormat) {
  for (uint8_t c = 0; c < kCodecCount; ++c) {
    const Codec codec = Codec(c);
    for (PixelFormat f : {PixelFormat::RGBA8, PixelFormat::RGBA16F, PixelFormat::RGBA32F}) {
      Piece p = samplePiece(f);
      Bytes m = encode(p, 11, codec);
      EXPECT_EQ(decodeHeader(m)->codec, codec);
      expectRoundTrip(p, m, decodePiece, Type::Piece);
    }
    Piece empty = samplePiece(PixelFormat::RGBA8);
    empty.active = {};
    empty.pixels.clear();
    expectRoundTrip(empty, encode(empty, 11, codec), decodePiece, Type::Piece);
    Strips s = sampleStrips();
    expectRoundTrip(s, encode(s, 11, codec), decodeStrips, Type::Strips);
    Framebuffer fb = sampleFramebuffer();
    expectRoundTrip(fb, encode(fb, 11, codec), decodeFramebuffer, Type::Framebuffer);
    // Compression does something: the stream is 70% zeros.
    if (codec != Codec::None) {
      EXPECT_LT(encode(s, 11, codec).size(), s.stream.size()) << codecName(codec);
    }
  }
}

template <class Dec>
void expectTruncationsFail(const Bytes& msg, Dec dec) {
  ASSERT_TRUE(dec(msg));
  for (size_t n = 0; n < msg.size(); ++n) {
    Bytes cut(msg.begin(), msg.begin() + n);  // own allocation so ASan sees any overread
    auto r = dec(cut);
    ASSERT_FALSE(r) << "accepted a message truncated to " << n << " of " << msg.size();
    EXPECT_FALSE(r.error().empty());
  }
}

TEST(Protocol, TruncatedAtEveryLengthFails) {
  expectTruncationsFail(encode(Hello{Role::Renderer, 1, "ipc://x"}, 1), decodeHello);
  expectTruncationsFail(encode(sampleParams(), 1), decodeFrameParams);
  expectTruncationsFail(encode(sampleSortFirstParams(), 1), decodeFrameParams);
  expectTruncationsFail(encode(samplePiece(PixelFormat::RGBA8), 1, Codec::Lzo), decodePiece);
  expectTruncationsFail(encode(sampleStrips(), 1, Codec::Zstd), decodeStrips);
  expectTruncationsFail(encode(sampleFramebuffer(), 1, Codec::Lz4), decodeFramebuffer);
  expectTruncationsFail(encode(Input{1, 2, 3, QualityName::Fast}, 1), decodeInput);
  expectTruncationsFail(encode(Probe{}, 1), decodeProbe);
}

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

TEST(Protocol, GarbageBytesFailEveryDecoder) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    Bytes g(rng() % 200);
    for (auto& b : g) b = std::byte(uint8_t(rng()));
    if (trial % 2 && g.size() >= kHeaderSize) {  // a valid frame around garbage: reaches the payload parsers
      putLE(g, 0, kMagic, 4);
      putLE(g, 4, kVersion, 2);
      putLE(g, 6, 1 + trial % kTypeCount, 2);
      putLE(g, 20, 0, 4);  // codec none, flags 0, reserved 0
      putLE(g, 24, g.size() - kHeaderSize, 4);
      reseal(g);
    }
    EXPECT_FALSE(decodeHello(g) && decodeWelcome(g) && decodeHeartbeat(g) && decodeShutdown(g) &&
                 decodeFrameParams(g) && decodePiece(g) && decodeStrips(g) && decodeStageStats(g) &&
                 decodeFrameDone(g) && decodeInput(g) && decodeProbe(g));
    // At most one decoder may accept any buffer: the type field picks it.
    int accepted = bool(decodeHello(g)) + bool(decodeWelcome(g)) + bool(decodeHeartbeat(g)) +
                   bool(decodeShutdown(g)) + bool(decodeFrameParams(g)) + bool(decodePiece(g)) +
                   bool(decodeStrips(g)) + bool(decodeStageStats(g)) + bool(decodeFrameDone(g)) +
                   bool(decodeInput(g)) + bool(decodeRoster(g)) + bool(decodeFramebuffer(g)) +
                   bool(decodeProbe(g));
    EXPECT_LE(accepted, 1);
  }
}

TEST(Protocol, FlippedPayloadByteFailsTheChecksum) {
  Bytes m = encode(samplePiece(PixelFormat::RGBA8), 1, Codec::Lz4);
  m[kHeaderSize + 20] ^= std::byte{0x10};
  auto r = decodePiece(m);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("checksum"), std::string::npos) << r.error();
}

TEST(Protocol, WrongVersionWrongTypeAndWrongSizeAreNamed) {
  Bytes m = encode(Heartbeat{Role::Renderer, 1}, 1);
  Bytes old = m;
  putLE(old, 4, 0, 2);
  auto r = decodeHeartbeat(old);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("version 0 != " + std::to_string(kVersion)), std::string::npos) << r.error();
  auto w = decodeWelcome(m);
  ASSERT_FALSE(w);
  EXPECT_NE(w.error().find("Heartbeat"), std::string::npos) << w.error();
  Bytes longer = m;
  longer.push_back(std::byte{0});
  auto l = decodeHeartbeat(longer);
  ASSERT_FALSE(l);
  EXPECT_NE(l.error().find("encoded_size"), std::string::npos) << l.error();
  Bytes trailing = m;
  trailing.push_back(std::byte{0});
  putLE(trailing, 24, trailing.size() - kHeaderSize, 4);  // raw_size too, so only the payload is wrong
  reseal(trailing);
  auto t = decodeHeartbeat(trailing);
  ASSERT_FALSE(t);
  EXPECT_NE(t.error().find("trailing"), std::string::npos) << t.error();
  Bytes magic = m;
  magic[0] = std::byte{'X'};
  EXPECT_FALSE(decodeHeartbeat(magic));
}

TEST(Protocol, OversizedRawSizeIsRejectedBeforeAllocating) {
  Bytes m = encode(sampleStrips(), 1, Codec::Zstd);
  putLE(m, 24, uint64_t(kMaxPayload) + 1, 4);
  auto r = decodeStrips(m);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("raw_size"), std::string::npos) << r.error();
  Bytes small = encode(sampleStrips(), 1, Codec::Lz4);
  putLE(small, 24, 8, 4);  // smaller than the metadata
  EXPECT_FALSE(decodeStrips(small));
}

TEST(Protocol, PieceActiveOutsideRegionIsRejected) {
  Piece p = samplePiece(PixelFormat::RGBA8);
  p.region = {0, 0, 16, 16};
  p.active = {10, 10, 20, 20};
  p.pixels.resize(size_t(20 * 20 * 4));
  auto r = decodePiece(encode(p, 1, Codec::Lzo));
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error(), "Piece: active 10,10 20x20 outside region 0,0 16x16");
  p.region = {-1, 0, 40, 40};
  auto neg = decodePiece(encode(p, 1, Codec::None));
  ASSERT_FALSE(neg);
  EXPECT_NE(neg.error().find("region"), std::string::npos) << neg.error();
}

TEST(Protocol, PiecePixelCountMustMatchActiveArea) {
  Piece p = samplePiece(PixelFormat::RGBA8);
  EXPECT_THROW(
      {
        Piece bad = p;
        bad.pixels.pop_back();
        encode(bad, 1, Codec::None);
      },
      std::invalid_argument);
  // A peer that lies: claims a larger active rect than its pixels cover.
  Bytes m = encode(p, 1, Codec::None);
  // Piece payload: epoch, renderer, brick (u32 each), region (4 x i32), active x, y, w, h.
  const size_t active_h = kHeaderSize + 12 + 16 + 12;
  ASSERT_EQ(uint8_t(m[active_h]), 9);
  putLE(m, active_h, 10, 4);  // active.h 9 -> 10
  reseal(m);
  auto r = decodePiece(m);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("pixel bytes"), std::string::npos) << r.error();
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

TEST(Protocol, StructuredMessagesMustUseCodecNone) {
  Bytes m = encode(Shutdown{"bye"}, 1);
  m[20] = std::byte{uint8_t(Codec::Lzo)};
  auto r = decodeShutdown(m);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("codec"), std::string::npos) << r.error();
}

// The master's probe used to be a Heartbeat posing as a Display; now it is its own type,
// and a Probe with any payload, or anything else, is not a Probe.
TEST(Protocol, ProbeIsEmptyAndDistinctFromHeartbeat) {
  Bytes probe = encode(Probe{}, 1);
  EXPECT_EQ(uint16_t(uint8_t(probe[6])), uint16_t(Type::Probe));
  EXPECT_EQ(Type::Last, Type::Probe);
  EXPECT_STREQ(typeName(Type::Probe), "Probe");
  EXPECT_FALSE(decodeHeartbeat(probe));
  auto hb = decodeProbe(encode(Heartbeat{Role::Display, 0}, 1));
  ASSERT_FALSE(hb);
  EXPECT_NE(hb.error().find("Heartbeat"), std::string::npos) << hb.error();
  Bytes trailing = probe;
  trailing.push_back(std::byte{0});
  putLE(trailing, 24, trailing.size() - kHeaderSize, 4);
  reseal(trailing);
  auto t = decodeProbe(trailing);
  ASSERT_FALSE(t);
  EXPECT_NE(t.error().find("trailing"), std::string::npos) << t.error();
  Bytes coded = probe;
  coded[20] = std::byte{uint8_t(Codec::Lz4)};
  EXPECT_FALSE(decodeProbe(coded));
}

// Enum ranges come from each enum's Last: one past it is unknown on the wire.
TEST(Protocol, RoleAndFormatRangesDeriveFromLast) {
  EXPECT_TRUE(validRole(uint8_t(Role::Last)));
  EXPECT_FALSE(validRole(uint8_t(Role::Last) + 1));
  EXPECT_FALSE(validRole(0));
  EXPECT_TRUE(validPixelFormat(uint8_t(PixelFormat::Last)));
  EXPECT_FALSE(validPixelFormat(uint8_t(PixelFormat::Last) + 1));
  EXPECT_FALSE(validPixelFormat(0));
  Bytes hb = encode(Heartbeat{Role::Renderer, 1}, 1);
  hb[kHeaderSize] = std::byte{uint8_t(uint8_t(Role::Last) + 1)};
  reseal(hb);
  auto r = decodeHeartbeat(hb);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("role"), std::string::npos) << r.error();
  FrameParams p = sampleParams();
  p.format = PixelFormat(uint8_t(PixelFormat::Last) + 1);
  auto f = decodeFrameParams(encode(p, 1));
  ASSERT_FALSE(f);
  EXPECT_NE(f.error().find("format"), std::string::npos) << f.error();
}

}  // namespace
}  // namespace tessera::proto
