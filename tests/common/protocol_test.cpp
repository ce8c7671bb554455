// Wire protocol: every message round-trips, and every kind of damage is a clean failure
// with a reason (never a crash, never a partially trusted message).
#include "common/wire/protocol.h"
#include "tests/common/protocol_samples.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>

namespace tessera::proto {
namespace {

using namespace test;

// The pixel decoders without a receiver's bound, as values (the bound is a defaulted argument).
Result<Piece> anyPiece(std::span<const std::byte> m) { return decodePiece(m); }
Result<Strips> anyStrips(std::span<const std::byte> m) { return decodeStrips(m); }
Result<Framebuffer> anyFramebuffer(std::span<const std::byte> m) { return decodeFramebuffer(m); }

TEST(Protocol, HeaderLayoutOnTheWire) {
  Bytes m = encode(Welcome{Role::Compositor, 5}, 77);
  ASSERT_EQ(m.size(), kHeaderSize + 21);  // role, rank, volume_range
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(m.data()), 4), "TSER");
  EXPECT_EQ(uint8_t(m[4]), kVersion);
  EXPECT_EQ(uint8_t(m[6]), uint8_t(Type::Welcome));
  EXPECT_EQ(uint8_t(m[16]), 77);  // sender after the u64 frame
  auto h = decodeHeader(m);
  ASSERT_TRUE(h) << h.error();
  EXPECT_EQ(h->type, Type::Welcome);
  EXPECT_EQ(h->sender, 77u);
  EXPECT_EQ(h->codec, Codec::None);
  EXPECT_EQ(h->raw_size, 21u);
  EXPECT_EQ(h->encoded_size, 21u);
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
  Hello hello{Role::Compositor, 4242, "tcp://127.0.0.1:7000", "3f9a0c1d2e4b", "image: [64, 48]\nblend: maximum\n"};
  expectRoundTrip(hello, encode(hello, 11), decodeHello, Type::Hello);
  expectRoundTrip(Welcome{Role::Display, 3}, encode(Welcome{Role::Display, 3}, 11), decodeWelcome, Type::Welcome);
  const Welcome ranged{Role::Renderer, 2, {-1024.5, 3071}};
  expectRoundTrip(ranged, encode(ranged, 11), decodeWelcome, Type::Welcome);
  // A range a renderer could not normalise with is refused, naming it.
  for (const std::array<double, 2> bad : {std::array<double, 2>{5, 5}, {7, 3}, {0, NAN}, {-INFINITY, 1}}) {
    const auto w = decodeWelcome(encode(Welcome{Role::Renderer, 2, bad}, 11));
    ASSERT_FALSE(w) << bad[0] << " " << bad[1];
    EXPECT_NE(w.error().find("volume_range"), std::string::npos) << w.error();
  }
  expectRoundTrip(Heartbeat{Role::Renderer, 9}, encode(Heartbeat{Role::Renderer, 9}, 11), decodeHeartbeat, Type::Heartbeat);
  expectRoundTrip(Probe{}, encode(Probe{}, 11), decodeProbe, Type::Probe);
  EXPECT_EQ(encode(Probe{}, 11).size(), kHeaderSize) << "Probe carries no payload";
  expectRoundTrip(Shutdown{"master exiting", "run-7"}, encode(Shutdown{"master exiting", "run-7"}, 11), decodeShutdown, Type::Shutdown);
  Roster roster{7, {{Role::Renderer, 0, std::string(16, '\x5a') + "d"}, {Role::Compositor, 3, "x"}}};
  expectRoundTrip(roster, encode(roster, 11), decodeRoster, Type::Roster);
  for (const FrameParams& fp : {sampleParams(), sampleSortFirstParams()}) {
    expectRoundTrip(fp, encode(fp, 11), decodeFrameParams, Type::FrameParams);
    EXPECT_EQ(decodeFrameParams(encode(fp, 11))->mode(), fp.mode());
  }
  StageStats st{Role::Compositor, 2, 99, 8, 4.5, 1.25, 0.75, 4000000, 700000, 12345, {1, 2, 300, 400}, 6, {1.5, 0.25}, 7, 3, 99, 5, 4, 812.5, 17, 40, 3, 1ull << 33, 12.25, 6.5};
  expectRoundTrip(st, encode(st, 11), decodeStageStats, Type::Stats);
  FrameDone fd{1000, 16.5, 2.25, 33.5, 888888, 3, 1};
  expectRoundTrip(fd, encode(fd, 11), decodeFrameDone, Type::FrameDone);
  Input in{12, -5.5, 10, 0.9, QualityName::Reference, true, 800, 600, TimeKey::Back, true, -0.125, 1.5};
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
      expectRoundTrip(p, m, anyPiece, Type::Piece);
    }
    Piece empty = samplePiece(PixelFormat::RGBA8);
    empty.active = {};
    empty.pixels.clear();
    expectRoundTrip(empty, encode(empty, 11, codec), anyPiece, Type::Piece);
    Strips s = sampleStrips();
    expectRoundTrip(s, encode(s, 11, codec), anyStrips, Type::Strips);
    Framebuffer fb = sampleFramebuffer();
    expectRoundTrip(fb, encode(fb, 11, codec), anyFramebuffer, Type::Framebuffer);
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
  expectTruncationsFail(encode(Hello{Role::Renderer, 1, "ipc://x", "run-a", "image: [8, 8]\n"}, 1), decodeHello);
  expectTruncationsFail(encode(sampleParams(), 1), decodeFrameParams);
  expectTruncationsFail(encode(sampleSortFirstParams(), 1), decodeFrameParams);
  expectTruncationsFail(encode(samplePiece(PixelFormat::RGBA8), 1, Codec::Lzo), anyPiece);
  expectTruncationsFail(encode(sampleStrips(), 1, Codec::Zstd), anyStrips);
  expectTruncationsFail(encode(sampleFramebuffer(), 1, Codec::Lz4), anyFramebuffer);
  expectTruncationsFail(encode(Input{9, 1, 2, 3, QualityName::Fast, true, 640, 480, TimeKey::Last, true, 0.5, 2}, 1), decodeInput);
  expectTruncationsFail(encode(Probe{}, 1), decodeProbe);
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

// A few KB of zstd can claim hundreds of MB of zeros: a receiver's bound (its frame's worth)
// refuses such a part before it allocates or decodes anything, naming both sizes.
TEST(Protocol, PartsLargerThanTheReceiversFrameAreRefusedBeforeDecoding) {
  Piece p = samplePiece(PixelFormat::RGBA32F);
  p.region = p.active = {0, 0, 1024, 1024};
  p.pixels.assign((size_t)16 << 20, std::byte{0});
  const Bytes piece = encode(p, 3, Codec::Zstd);
  ASSERT_LT(piece.size(), 4096u);
  auto r = decodePiece(piece, (size_t)16 << 20);
  ASSERT_TRUE(r) << r.error();
  r = decodePiece(piece, ((size_t)16 << 20) - 1);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("Piece: 16777216 pixel bytes, more than the 16777215 this stage's frames can hold"),
            std::string::npos)
      << r.error();
  Strips s = sampleStrips();
  s.stream.assign((size_t)1 << 20, 0);
  const Bytes strips = encode(s, 1, Codec::Zstd);
  EXPECT_TRUE(decodeStrips(strips, (size_t)1 << 20));
  auto rs = decodeStrips(strips, 1000);
  ASSERT_FALSE(rs);
  EXPECT_NE(rs.error().find("Strips: 1048576 pixel bytes, more than the 1000"), std::string::npos) << rs.error();
  Framebuffer f = sampleFramebuffer();
  f.width = f.height = 512;
  f.pixels.assign((size_t)512 * 512 * 4, std::byte{0});
  const Bytes fb = encode(f, 1, Codec::Zstd);
  EXPECT_TRUE(decodeFramebuffer(fb, f.pixels.size()));
  auto rf = decodeFramebuffer(fb, f.pixels.size() - 1);
  ASSERT_FALSE(rf);
  EXPECT_NE(rf.error().find("Framebuffer: 1048576 pixel bytes, more than"), std::string::npos) << rf.error();
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

TEST(Protocol, StructuredMessagesMustUseCodecNone) {
  Bytes m = encode(Shutdown{"bye", ""}, 1);
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

TEST(Protocol, InteractionFieldsOutOfRangeAreRefusedByName) {
  FrameParams p = sampleParams();
  p.first_wanted = p.frame + 1;  // a frame cannot cancel itself
  auto f = decodeFrameParams(encode(p, 1));
  ASSERT_FALSE(f);
  EXPECT_NE(f.error().find("first_wanted 43 after the frame itself (42)"), std::string::npos) << f.error();
  p = sampleParams();
  p.input_first = p.input_seq + 1;  // the first input a frame answers is not after its newest
  f = decodeFrameParams(encode(p, 1));
  ASSERT_FALSE(f);
  EXPECT_NE(f.error().find("input_first 78 after input_seq 77"), std::string::npos) << f.error();
  for (auto [w, h] : {std::pair{0, 5}, std::pair{-1, -1}, std::pair{16385, 10}}) {
    Input in;
    in.width = w;
    in.height = h;
    auto r = decodeInput(encode(in, 1));
    ASSERT_FALSE(r) << w << "x" << h;
    EXPECT_NE(r.error().find("window size"), std::string::npos) << r.error();
  }
  for (double scale : {0.0, -1.0, std::nan("")}) {  // the colour window's width factor
    Input in;
    in.window_scale = scale;
    auto r = decodeInput(encode(in, 1));
    ASSERT_FALSE(r) << scale;
    EXPECT_NE(r.error().find("window_scale"), std::string::npos) << r.error();
  }
  for (ColorWindow w : {ColorWindow{0.5, 0}, ColorWindow{0.5, -1}, ColorWindow{2e6, 1}, ColorWindow{0.5, 2e6}}) {
    p = sampleParams();
    p.window = w;
    f = decodeFrameParams(encode(p, 1));
    ASSERT_FALSE(f) << w.center << " " << w.width;
    EXPECT_NE(f.error().find("colour window"), std::string::npos) << f.error();
  }
  FrameDone d;
  d.input_ms = -1;
  auto r = decodeFrameDone(encode(d, 1));
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().find("input_ms"), std::string::npos) << r.error();
}

}  // namespace
}  // namespace tessera::proto
