#include "common/wire/row_filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "common/wire/codec.h"
#include "common/wire/protocol.h"
#include "common/wire/strips.h"
#include "tests/common/protocol_samples.h"
#include "tests/common/random_bytes.h"

namespace tessera {
namespace {

TEST(RowFilter, UndoesItselfForAnyPlanesAndRows) {
  for (size_t planes : {1, 2, 4})
    for (size_t row_bytes : {1, 4, 7, 64})
      for (size_t rows : {0, 1, 2, 9}) {
        const auto raw = randomBytes(planes * row_bytes * rows, uint32_t(planes * 1000 + row_bytes * 10 + rows));
        std::vector<std::byte> f(raw.size());
        upFilter(raw, f, row_bytes, planes);
        upUnfilter(f, row_bytes, planes);
        EXPECT_EQ(f, raw) << planes << " planes of " << rows << " rows of " << row_bytes;
      }
}

TEST(RowFilter, KeepsEachPlanesFirstRowAndSubtractsTheRowAbove) {
  // Two planes of two rows of three bytes.
  const std::vector<uint8_t> in = {10, 20, 30, 11, 19, 32, /* plane 2 */ 200, 0, 5, 199, 255, 5};
  std::vector<std::byte> f(in.size());
  upFilter(std::as_bytes(std::span(in)), f, 3, 2);
  const std::vector<uint8_t> want = {10, 20, 30, 1, 255, 2, 200, 0, 5, 255, 255, 0};
  for (size_t i = 0; i < in.size(); ++i) EXPECT_EQ(uint8_t(f[i]), want[i]) << "byte " << i;
}

// The filter is applied on the wire: rows that differ from the row above by a constant
// compress to almost nothing, which the codec alone (no filter) cannot do with random rows.
TEST(RowFilter, PiecesTravelFiltered) {
  proto::Piece p;
  p.region = {0, 0, 256, 64};
  p.active = p.region;
  p.format = proto::PixelFormat::RGBA8;
  const auto base = randomBytes(256 * 4, 7);
  for (int y = 0; y < 64; ++y)
    for (auto b : base) p.pixels.push_back(std::byte(uint8_t(uint8_t(b) + y)));
  ASSERT_GT(compress(Codec::Lzo, p.pixels).size(), p.pixels.size() * 9 / 10) << "the codec alone cannot shrink it";
  const auto msg = proto::encode(p, 1, Codec::Lzo);
  EXPECT_LT(msg.size(), p.pixels.size() / 5);
  auto back = proto::decodePiece(msg);
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(back->pixels, p.pixels);
}

TEST(StripFilter, UndoesItselfForAnyStripLengthAndCount) {
  for (size_t strip : {12, 16, 8 + 4 * 33})
    for (size_t strips : {0, 1, 2, 7}) {
      const auto raw = randomBytes(strip * strips, uint32_t(strip * 10 + strips));
      std::vector<std::byte> f(raw.size());
      stripFilter(raw, f, strip);
      stripUnfilter(f, strip);
      EXPECT_EQ(f, raw) << strips << " strips of " << strip << " bytes";
    }
}

TEST(StripFilter, SplitsEachStripsChannelsThenSubtractsTheStripBefore) {
  // Two strips of a header and two pixels.
  const std::vector<uint8_t> in = {1, 2, 3, 4, 5, 6, 7, 8, /* px */ 10, 20, 30, 40, 11, 21, 31, 41,
                                   1, 2, 4, 4, 5, 6, 7, 9, /* px */ 12, 20, 30, 40, 11, 22, 33, 44};
  std::vector<std::byte> f(in.size());
  stripFilter(std::as_bytes(std::span(in)), f, 16);
  const std::vector<uint8_t> want = {1, 2, 3, 4, 5, 6, 7, 8, 10, 11, 20, 21, 30, 31, 40, 41,
                                     0, 0, 1, 0, 0, 0, 0, 1, 2, 0, 0, 1, 0, 2, 0, 3};
  for (size_t i = 0; i < in.size(); ++i) EXPECT_EQ(uint8_t(f[i]), want[i]) << "byte " << i;
}

// A band whose rows differ by a constant: strip-filtered on the wire it compresses to almost
// nothing; a stream of strips of two widths travels as it is. Both arrive unchanged.
TEST(StripFilter, StripsOfOneWidthTravelFiltered) {
  Image8 img(256, 64);
  const auto base = randomBytes(256 * 4, 9);
  for (int y = 0; y < 64; ++y)
    for (size_t i = 0; i < base.size(); ++i) img.px[size_t(y) * base.size() + i] = uint8_t(uint8_t(base[i]) + y);
  proto::Strips s;
  s.stream = encodeStrips(img, {0, 0, 256, 64}, 0);
  ASSERT_EQ(uniformStripBytes(s.stream), 8 + 4 * 256u);
  ASSERT_GT(compress(Codec::Lzo, std::as_bytes(std::span(s.stream))).size(), s.stream.size() * 9 / 10);
  const auto msg = proto::encode(s, 1, Codec::Lzo);
  EXPECT_LT(msg.size(), s.stream.size() / 5);
  auto back = proto::decodeStrips(msg);
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(back->stream, s.stream);

  auto narrower = encodeStrips(img, {0, 0, 100, 3}, 0);
  s.stream.insert(s.stream.end(), narrower.begin(), narrower.end());
  EXPECT_EQ(uniformStripBytes(s.stream), 0u);
  const auto mixed = proto::encode(s, 1, Codec::Lzo);
  EXPECT_GT(mixed.size(), s.stream.size() * 9 / 10) << "two widths: unfiltered";
  back = proto::decodeStrips(mixed);
  ASSERT_TRUE(back) << back.error();
  EXPECT_EQ(back->stream, s.stream);
}

// strip_bytes comes from the sender: one that does not cut the stream into strips of a
// header and whole pixels is refused before anything is decompressed.
TEST(StripFilter, AStripLengthThatDoesNotFitTheStreamIsRefused) {
  Image8 img(16, 4);
  for (auto& b : img.px) b = 7;
  proto::Strips s;
  s.stream = encodeStrips(img, {0, 0, 16, 4}, 0);
  auto msg = proto::encode(s, 1, Codec::Lzo);
  const size_t at = proto::kHeaderSize + 40;  // strip_bytes, after the other metadata
  uint32_t sent = 0;
  for (int i = 0; i < 4; ++i) sent |= uint32_t(msg[at + i]) << (8 * i);
  ASSERT_EQ(sent, 8 + 4 * 16u);
  for (uint64_t bad : {5ull, 8ull, 8 + 4 * 16 + 2ull, 8 + 4 * 15ull, 8 + 4 * 16 * 4 * 2ull, 0xFFFFFFF8ull}) {
    auto m = msg;
    proto::test::putLE(m, at, bad, 4);
    proto::test::reseal(m);
    auto r = proto::decodeStrips(m);
    ASSERT_FALSE(r) << bad;
    EXPECT_NE(r.error().find("strip_bytes " + std::to_string(bad)), std::string::npos) << r.error();
  }
  // An empty stream (a transparent band) with a strip length: nothing to undo, and no
  // allocation of the length it claims.
  proto::Strips none;
  auto empty = proto::encode(none, 1, Codec::Lzo);
  proto::test::putLE(empty, at, 0xFFFFFFF8u, 4);
  proto::test::reseal(empty);
  EXPECT_FALSE(proto::decodeStrips(empty));
  // Without a codec the filter would gain nothing: the stream travels as it is.
  const auto plain = proto::encode(s, 1, Codec::None);
  ASSERT_EQ(plain.size(), proto::kHeaderSize + 44 + s.stream.size());
  EXPECT_EQ(uint8_t(plain[at]) | uint8_t(plain[at + 1]) | uint8_t(plain[at + 2]) | uint8_t(plain[at + 3]), 0);
  EXPECT_TRUE(std::equal(s.stream.begin(), s.stream.end(), reinterpret_cast<const uint8_t*>(plain.data()) + at + 4));
}

}  // namespace
}  // namespace tessera
