// Strip headers: encoding, routing a strip stream, and the sort-first framebuffer packing.
// Routing trusts nothing in the stream: every header is checked before a pixel is written.
#include "common/wire/strips.h"

#include <algorithm>
#include <cstring>
#include <numeric>
#include <stdexcept>
#include <string>

namespace tessera {
namespace {

constexpr uint8_t kCheckSalt = 0xA5;  // so an all-zero header (gap pixels) never checks
constexpr size_t kHeaderBytes = 4 * kStripHeaderPixels;
constexpr int kMaxCoord = 0xFFFF;

uint8_t checkByte(const uint8_t in[8]) {
  uint8_t c = kCheckSalt;
  for (int i = 0; i < 7; ++i) c ^= in[i];
  return c;
}

bool rowIsEmpty(const uint8_t* p, int width) {
  for (int i = 0; i < 4 * width; ++i) {
    if (p[i] != 0) return false;
  }
  return true;
}

// Where a checked header may write: the whole strip must lie inside dst (and dst must
// really hold width*height pixels, so a malformed Image8 cannot be overrun either).
bool fits(const StripHeader& h, const Image8& dst) {
  return h.width > 0 && int(h.x) + int(h.width) <= dst.width && int(h.y) < dst.height &&
         dst.px.size() >= 4 * size_t(dst.width) * size_t(dst.height);
}

}  // namespace

void packHeader(const StripHeader& h, uint8_t out[8]) {
  out[0] = uint8_t(h.x & 0xFF);
  out[1] = uint8_t(h.x >> 8);
  out[2] = uint8_t(h.y & 0xFF);
  out[3] = uint8_t(h.y >> 8);
  out[4] = uint8_t(h.width & 0xFF);
  out[5] = uint8_t(h.width >> 8);
  out[6] = h.display;
  out[7] = checkByte(out);
}

bool unpackHeader(const uint8_t in[8], StripHeader& h) {
  if (checkByte(in) != in[7]) return false;
  h.x = uint16_t(in[0] | (in[1] << 8));
  h.y = uint16_t(in[2] | (in[3] << 8));
  h.width = uint16_t(in[4] | (in[5] << 8));
  h.display = in[6];
  return true;
}

std::vector<uint8_t> encodeStrips(const Image8& img, const Rect& r, uint8_t display) {
  // Clip to the image: pixels outside it do not exist.
  int x0 = std::max(r.x, 0), y0 = std::max(r.y, 0);
  int x1 = std::min(r.x + std::max(r.w, 0), img.width), y1 = std::min(r.y + std::max(r.h, 0), img.height);
  std::vector<uint8_t> out;
  if (x1 <= x0 || y1 <= y0) return out;
  if (x1 - x0 > kMaxCoord || y1 - 1 > kMaxCoord || x0 > kMaxCoord) {
    throw std::invalid_argument("encodeStrips: rect exceeds 16-bit header coordinates");
  }
  const int w = x1 - x0;
  out.reserve(size_t(y1 - y0) * (kHeaderBytes + 4 * size_t(w)));
  for (int y = y0; y < y1; ++y) {
    const uint8_t* row = img.at(x0, y);
    if (rowIsEmpty(row, w)) continue;
    uint8_t hdr[8];
    packHeader({uint16_t(x0), uint16_t(y), uint16_t(w), display}, hdr);
    out.insert(out.end(), hdr, hdr + 8);
    out.insert(out.end(), row, row + 4 * size_t(w));
  }
  return out;
}

size_t uniformStripBytes(std::span<const uint8_t> stream) {
  StripHeader first, h;
  if (stream.size() < kHeaderBytes || !unpackHeader(stream.data(), first) || first.width == 0) return 0;
  const size_t strip = kHeaderBytes + 4 * size_t(first.width);
  if (stream.size() % strip != 0) return 0;
  for (size_t at = strip; at < stream.size(); at += strip)
    if (!unpackHeader(stream.data() + at, h) || h.width != first.width) return 0;
  return strip;
}

RouteStats routeStrips(std::span<const uint8_t> stream, Image8& dst, uint8_t display) {
  return routeStrips(stream, dst, display, Rect{0, 0, dst.width, dst.height});
}

RouteStats routeStrips(std::span<const uint8_t> stream, Image8& dst, uint8_t display, const Rect& within) {
  RouteStats s;
  size_t pos = 0;
  while (pos < stream.size()) {
    if (stream.size() - pos < kHeaderBytes) {
      s.truncated = true;
      break;
    }
    StripHeader h;
    if (!unpackHeader(stream.data() + pos, h)) {
      // Without a trusted width there is no way to find the next header.
      ++s.strips_rejected;
      break;
    }
    pos += kHeaderBytes;
    const size_t bytes = 4 * size_t(h.width);
    if (stream.size() - pos < bytes) {
      s.truncated = true;
      break;
    }
    const bool inside = h.x >= within.x && h.y >= within.y && h.y < within.y + within.h &&
                        int(h.x) + int(h.width) <= within.x + within.w;
    if (h.display != display || !fits(h, dst) || !inside) {
      ++s.strips_rejected;
    } else {
      std::memcpy(dst.at(h.x, h.y), stream.data() + pos, bytes);
      ++s.strips_written;
      s.pixels_written += h.width;
    }
    pos += bytes;
  }
  return s;
}

TilePacking packTiles(const std::vector<Rect>& tiles, int max_fb_width) {
  // Shelf packing, tallest first (next-fit decreasing height). Heights never increase
  // from left to right within a shelf, so on every framebuffer row the tiles that still
  // have pixels form an unbroken run from x = 0: the router stops at the first gap.
  TilePacking p;
  p.tiles.resize(tiles.size());
  std::vector<size_t> idx(tiles.size());
  std::iota(idx.begin(), idx.end(), size_t{0});
  std::stable_sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return tiles[a].h > tiles[b].h; });
  int cursor_x = 0, shelf_y = 0, shelf_h = 0;
  for (size_t i : idx) {
    const Rect& t = tiles[i];
    p.tiles[i] = {t, 0, 0};
    if (t.empty()) continue;  // no pixels, no header, no space
    const int span = kStripHeaderPixels + t.w;
    if (cursor_x > 0 && cursor_x + span > max_fb_width) {
      shelf_y += shelf_h;
      cursor_x = 0;
      shelf_h = 0;
    }
    p.tiles[i].fb_x = cursor_x + kStripHeaderPixels;
    p.tiles[i].fb_y = shelf_y;
    cursor_x += span;
    shelf_h = std::max(shelf_h, t.h);
    p.fb_width = std::max(p.fb_width, cursor_x);
  }
  p.fb_height = shelf_y + shelf_h;
  return p;
}

void writeTileHeaders(const TilePacking& p, Image8& fb, uint8_t display) {
  for (const PackedTile& t : p.tiles) {
    if (t.dst.empty()) continue;
    if (t.fb_x < kStripHeaderPixels || t.fb_x + t.dst.w > fb.width || t.fb_y < 0 || t.fb_y + t.dst.h > fb.height) {
      throw std::invalid_argument("writeTileHeaders: tile at fb " + std::to_string(t.fb_x) + "," +
                                  std::to_string(t.fb_y) + " does not fit the framebuffer");
    }
    if (t.dst.x < 0 || t.dst.y < 0 || t.dst.x > kMaxCoord || t.dst.w > kMaxCoord || t.dst.y + t.dst.h - 1 > kMaxCoord) {
      throw std::invalid_argument("writeTileHeaders: tile exceeds 16-bit header coordinates");
    }
    for (int row = 0; row < t.dst.h; ++row) {
      packHeader({uint16_t(t.dst.x), uint16_t(t.dst.y + row), uint16_t(t.dst.w), display},
                 fb.at(t.fb_x - kStripHeaderPixels, t.fb_y + row));
    }
  }
}

RouteStats routeFramebuffer(const Image8& fb, Image8& dst, uint8_t display, std::span<const Rect> allowed) {
  auto inside = [&](const StripHeader& h) {
    if (allowed.empty()) return true;
    return std::any_of(allowed.begin(), allowed.end(), [&](const Rect& t) {
      return h.y >= t.y && h.y < t.y + t.h && h.x >= t.x && h.x + h.width <= t.x + t.w;
    });
  };
  RouteStats s;
  if (fb.width <= 0 || fb.height <= 0 || fb.px.size() < 4 * size_t(fb.width) * size_t(fb.height)) return s;
  for (int y = 0; y < fb.height; ++y) {
    int x = 0;
    while (x + kStripHeaderPixels <= fb.width) {
      StripHeader h;
      if (!unpackHeader(fb.at(x, y), h)) break;  // a gap or unused pixels: the row is done
      x += kStripHeaderPixels;
      if (x + int(h.width) > fb.width) {
        s.truncated = true;
        break;
      }
      if (h.display != display || !fits(h, dst) || !inside(h)) {
        ++s.strips_rejected;
      } else {
        std::memmove(dst.at(h.x, h.y), fb.at(x, y), 4 * size_t(h.width));
        ++s.strips_written;
        s.pixels_written += h.width;
      }
      x += h.width;
    }
  }
  return s;
}

}  // namespace tessera
