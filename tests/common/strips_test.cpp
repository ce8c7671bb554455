// Strip headers: exact round trips, and hostile streams that must be rejected and counted
// without a single byte written outside the destination.
#include "common/wire/strips.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

namespace tessera {
namespace {

// Random opaque-ish pixels, with every third row fully transparent (so it is skipped).
Image8 testImage(int w, int h, uint32_t seed) {
  Image8 img(w, h);
  std::mt19937 rng(seed);
  for (int y = 0; y < h; ++y) {
    if (y % 3 == 2) continue;
    for (int x = 0; x < w; ++x) {
      uint8_t* p = img.at(x, y);
      for (int c = 0; c < 4; ++c) p[c] = uint8_t(rng());
      p[3] |= 1;  // alpha > 0
    }
  }
  return img;
}

// Everything outside r zeroed: what a router fed only r's strips must produce.
Image8 onlyRect(const Image8& img, const Rect& r) {
  Image8 out(img.width, img.height);
  for (int y = r.y; y < r.y + r.h; ++y) std::memcpy(out.at(r.x, y), img.at(r.x, y), 4 * size_t(r.w));
  return out;
}

std::vector<uint8_t> strip(StripHeader h, uint8_t fill) {
  std::vector<uint8_t> s(8 + 4 * size_t(h.width), fill);
  packHeader(h, s.data());
  return s;
}

void append(std::vector<uint8_t>& a, const std::vector<uint8_t>& b) { a.insert(a.end(), b.begin(), b.end()); }

TEST(StripHeader, PacksAndChecks) {
  StripHeader h{513, 7, 1000, 3}, back;
  uint8_t b[8];
  packHeader(h, b);
  EXPECT_EQ(b[0], 1);  // x = 0x0201, little-endian
  EXPECT_EQ(b[1], 2);
  ASSERT_TRUE(unpackHeader(b, back));
  EXPECT_EQ(back, h);
  for (int bit = 0; bit < 64; ++bit) {  // any single-bit error is detected by the xor check
    uint8_t c[8];
    std::memcpy(c, b, 8);
    c[bit / 8] ^= uint8_t(1 << (bit % 8));
    EXPECT_FALSE(unpackHeader(c, back)) << "bit " << bit;
  }
  const uint8_t zeros[8] = {};
  EXPECT_FALSE(unpackHeader(zeros, back)) << "gap pixels must never pass as a header";
}

TEST(Strips, EncodeRouteRoundTripIsExactAndSkipsEmptyRows) {
  Image8 img = testImage(40, 30, 1);
  const Rect r{5, 4, 27, 19};
  auto stream = encodeStrips(img, r, 2);
  // Rows 4..22; rows with y % 3 == 2 (5, 8, ..., 20: six rows) are transparent.
  const int rows = 19 - 6;
  EXPECT_EQ(stream.size(), size_t(rows) * (8 + 4 * 27));
  Image8 dst(40, 30);
  RouteStats s = routeStrips(stream, dst, 2);
  EXPECT_EQ(s, (RouteStats{rows, 0, false, rows * 27u}));
  EXPECT_EQ(dst, onlyRect(img, r));
}

TEST(Strips, EncodeClipsToTheImage) {
  Image8 img = testImage(10, 10, 2);
  auto stream = encodeStrips(img, {-3, 8, 20, 10}, 0);  // clips to 0,8 10x2; row 8 is transparent
  Image8 dst(10, 10);
  EXPECT_EQ(routeStrips(stream, dst, 0), (RouteStats{1, 0, false, 10}));
  EXPECT_EQ(dst, onlyRect(img, {0, 8, 10, 2}));
  EXPECT_TRUE(encodeStrips(img, {3, 3, 0, 5}, 0).empty());
}

TEST(Strips, HeadersPointingOutsideDstAreRejectedCountedAndNotWritten) {
  Image8 dst(16, 8);
  std::vector<uint8_t> stream;
  append(stream, strip({10, 0, 7, 1}, 0xEE));   // x + width = 17 > 16
  append(stream, strip({0, 8, 4, 1}, 0xEE));    // y = height
  append(stream, strip({65535, 0, 1, 1}, 0xEE));
  append(stream, strip({0, 0, 0, 1}, 0xEE));    // zero width
  append(stream, strip({3, 2, 4, 0}, 0xEE));    // other display id
  EXPECT_EQ(routeStrips(stream, dst, 1), (RouteStats{0, 5, false}));
  EXPECT_EQ(dst, Image8(16, 8)) << "a rejected strip wrote pixels";
  // Rejected strips are skipped by their (checked) width: a good strip after them lands.
  append(stream, strip({10, 7, 6, 1}, 0x11));
  EXPECT_EQ(routeStrips(stream, dst, 1), (RouteStats{1, 5, false, 6}));
  EXPECT_EQ(dst.at(10, 7)[0], 0x11);
  EXPECT_EQ(dst.at(15, 7)[3], 0x11);
  EXPECT_EQ(dst.at(9, 7)[0], 0);
}

// The display routes each sender's strips within the part of the image it owns (a
// compositor's region, a renderer's binary-swap band): one cannot write over another's.
TEST(Strips, StripsOutsideTheSendersPartAreRejected) {
  Image8 dst(16, 8);
  const Rect owned{0, 2, 16, 3};  // rows 2..4
  std::vector<uint8_t> stream;
  append(stream, strip({0, 1, 4, 1}, 0xEE));   // above
  append(stream, strip({0, 5, 4, 1}, 0xEE));   // below
  append(stream, strip({2, 3, 5, 1}, 0x22));   // inside
  EXPECT_EQ(routeStrips(stream, dst, 1, owned), (RouteStats{1, 2, false, 5}));
  EXPECT_EQ(dst.at(2, 3)[0], 0x22);
  EXPECT_EQ(dst.at(0, 1)[0], 0);
  EXPECT_EQ(dst.at(0, 5)[0], 0);
  Image8 narrow(16, 8);
  EXPECT_EQ(routeStrips(stream, narrow, 1, {3, 0, 4, 8}), (RouteStats{0, 3, false})) << "x 2..6 is not inside x 3..6";
}

TEST(Strips, BadCheckByteRejectsAndStopsTheStream) {
  Image8 dst(16, 8);
  std::vector<uint8_t> stream = strip({0, 0, 4, 0}, 0x22);
  stream[7] ^= 0x40;
  append(stream, strip({0, 1, 4, 0}, 0x22));  // cannot be found: the bad header's width is untrusted
  EXPECT_EQ(routeStrips(stream, dst, 0), (RouteStats{0, 1, false}));
  EXPECT_EQ(dst, Image8(16, 8));
}

TEST(Strips, TruncatedStreamIsFlaggedAndOnlyWholeStripsLand) {
  Image8 img = testImage(12, 6, 3);
  auto stream = encodeStrips(img, {0, 0, 12, 2}, 0);  // rows 0 and 1
  ASSERT_EQ(stream.size(), 2 * size_t(8 + 48));
  for (size_t cut : {size_t(1), size_t(7), size_t(8), size_t(30), size_t(56 + 3), size_t(56 + 50)}) {
    Image8 dst(12, 6);
    RouteStats s = routeStrips(std::span(stream).first(cut), dst, 0);
    EXPECT_TRUE(s.truncated) << "cut " << cut;
    EXPECT_EQ(s.strips_written, cut >= 56 ? 1 : 0) << "cut " << cut;
    EXPECT_EQ(dst, onlyRect(img, {0, 0, 12, cut >= 56 ? 1 : 0})) << "cut " << cut;
  }
  Image8 dst(12, 6);
  EXPECT_EQ(routeStrips({}, dst, 0), (RouteStats{}));
}

TEST(Strips, MalformedDstIsNeverOverrun) {
  Image8 dst;
  dst.width = 100;  // claims pixels it does not have
  dst.height = 100;
  auto stream = strip({0, 0, 4, 0}, 0x33);
  EXPECT_EQ(routeStrips(stream, dst, 0), (RouteStats{0, 1, false}));
}

// Builds a renderer framebuffer from the packing: tile pixels copied from `img`, headers
// written, everything else zero.
Image8 packedFramebuffer(const Image8& img, const TilePacking& p, uint8_t display) {
  Image8 fb(p.fb_width, p.fb_height);
  for (const PackedTile& t : p.tiles) {
    for (int row = 0; row < t.dst.h; ++row) {
      std::memcpy(fb.at(t.fb_x, t.fb_y + row), img.at(t.dst.x, t.dst.y + row), 4 * size_t(t.dst.w));
    }
  }
  writeTileHeaders(p, fb, display);
  return fb;
}

// No two tiles (with their header columns) overlap in the framebuffer, and all fit.
void expectDisjointInside(const TilePacking& p) {
  std::vector<int> owner(size_t(p.fb_width) * p.fb_height, -1);
  for (size_t i = 0; i < p.tiles.size(); ++i) {
    const PackedTile& t = p.tiles[i];
    if (t.dst.empty()) continue;
    ASSERT_GE(t.fb_x, kStripHeaderPixels);
    ASSERT_LE(t.fb_x + t.dst.w, p.fb_width);
    ASSERT_LE(t.fb_y + t.dst.h, p.fb_height);
    for (int y = t.fb_y; y < t.fb_y + t.dst.h; ++y) {
      for (int x = t.fb_x - kStripHeaderPixels; x < t.fb_x + t.dst.w; ++x) {
        int& o = owner[size_t(y) * p.fb_width + x];
        ASSERT_EQ(o, -1) << "tiles " << o << " and " << i << " overlap at " << x << "," << y;
        o = int(i);
      }
    }
  }
}

TEST(PackTiles, NonUniformTilesRouteBackExactly) {
  // 37x23 cut into uneven tiles, including 1-pixel-wide and 1-pixel-tall ones.
  const std::vector<Rect> tiles = {{0, 0, 10, 7},  {10, 0, 1, 7},  {11, 0, 26, 7}, {0, 7, 13, 16},
                                   {13, 7, 24, 1}, {13, 8, 24, 9}, {13, 17, 1, 6}, {14, 17, 23, 6}};
  Image8 img(37, 23);
  {
    std::mt19937 rng(4);
    for (auto& b : img.px) b = uint8_t(rng() | 1);  // no zero bytes: every pixel is content
  }
  for (int max_w : {1, 20, 40, 64, 1000}) {
    TilePacking p = packTiles(tiles, max_w);
    ASSERT_EQ(p.tiles.size(), tiles.size());
    for (size_t i = 0; i < tiles.size(); ++i) EXPECT_EQ(p.tiles[i].dst, tiles[i]);
    expectDisjointInside(p);
    int widest = 0;
    for (const Rect& t : tiles) widest = std::max(widest, t.w + kStripHeaderPixels);
    EXPECT_LE(p.fb_width, std::max(max_w, widest)) << "max_w " << max_w;
    Image8 fb = packedFramebuffer(img, p, 5);
    Image8 dst(37, 23);
    RouteStats s = routeFramebuffer(fb, dst, 5);
    // One strip per tile row (the sum of the tile heights); the tiles cover all 37x23 pixels.
    EXPECT_EQ(s, (RouteStats{59, 0, false, 37 * 23})) << "max_w " << max_w;
    EXPECT_EQ(dst, img) << "max_w " << max_w;
    Image8 other(37, 23);
    EXPECT_EQ(routeFramebuffer(fb, other, 4).strips_written, 0) << "display 4 took display 5's strips";
    EXPECT_EQ(routeFramebuffer(fb, other, 4).pixels_written, 0u);
  }
}

TEST(PackTiles, ShelvesAndWidthCap) {
  // Equal tiles 8 wide: three per 30-pixel shelf (3 * (2 + 8) = 30).
  std::vector<Rect> tiles;
  for (int i = 0; i < 7; ++i) tiles.push_back({8 * i, 0, 8, 5});
  TilePacking p = packTiles(tiles, 30);
  EXPECT_EQ(p.fb_width, 30);
  EXPECT_EQ(p.fb_height, 15);
  EXPECT_EQ(p.tiles[3].fb_x, 2);
  EXPECT_EQ(p.tiles[3].fb_y, 5);
  EXPECT_EQ(p.tiles[2].fb_x, 22);
  // A single tile wider than the cap widens the framebuffer rather than failing.
  TilePacking wide = packTiles({{0, 0, 50, 2}, {0, 2, 4, 2}}, 30);
  EXPECT_EQ(wide.fb_width, 52);
  EXPECT_EQ(wide.fb_height, 4);
  EXPECT_EQ(packTiles({}, 30).fb_width, 0);
}

TEST(RouteFramebuffer, CorruptHeaderEndsOnlyItsRow) {
  Image8 img(8, 4);
  for (auto& b : img.px) b = 0x7F;
  TilePacking p = packTiles({{0, 0, 4, 4}, {4, 0, 4, 4}}, 100);  // one shelf, two tiles side by side
  Image8 fb = packedFramebuffer(img, p, 0);
  fb.at(0, 1)[7] ^= 0x01;  // check byte of row 1's first header (second header pixel)
  Image8 dst(8, 4);
  RouteStats s = routeFramebuffer(fb, dst, 0);
  EXPECT_EQ(s, (RouteStats{6, 0, false, 6 * 4}));
  EXPECT_EQ(dst.at(0, 1)[0], 0);
  EXPECT_EQ(dst.at(7, 1)[0], 0) << "the row ends at a failed header";
  EXPECT_EQ(dst.at(7, 2)[0], 0x7F);
}

// A renderer's strips land only in its own tiles: a framebuffer packed for two tiles, of
// which the sender owns one, writes that one and has the other's strips rejected.
TEST(RouteFramebuffer, StripsOutsideTheSendersTilesAreRejected) {
  Image8 img(8, 4);
  for (auto& b : img.px) b = 0x7F;
  TilePacking p = packTiles({{0, 0, 4, 4}, {4, 0, 4, 4}}, 100);
  Image8 fb = packedFramebuffer(img, p, 0);
  Image8 dst(8, 4);
  const Rect own[] = {{0, 0, 4, 4}};
  EXPECT_EQ(routeFramebuffer(fb, dst, 0, own), (RouteStats{4, 4, false, 4 * 4}));
  EXPECT_EQ(dst.at(3, 3)[0], 0x7F);
  EXPECT_EQ(dst.at(4, 0)[0], 0) << "another renderer's tile was written";
  const Rect both[] = {{0, 0, 4, 4}, {4, 0, 4, 4}};
  EXPECT_EQ(routeFramebuffer(fb, dst, 0, both), (RouteStats{8, 0, false, 8 * 4}));
}

TEST(RouteFramebuffer, StripRunningPastTheRowIsTruncation) {
  Image8 fb(10, 1);
  packHeader({0, 0, 9, 0}, fb.at(0, 0));  // needs 2 + 9 > 10 pixels
  Image8 dst(16, 1);
  EXPECT_EQ(routeFramebuffer(fb, dst, 0), (RouteStats{0, 0, true}));
  EXPECT_EQ(dst, Image8(16, 1));
}

}  // namespace
}  // namespace tessera
