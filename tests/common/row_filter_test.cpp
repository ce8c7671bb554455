#include "common/wire/row_filter.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "common/wire/codec.h"
#include "common/wire/protocol.h"
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

}  // namespace
}  // namespace tessera
