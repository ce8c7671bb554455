// Lightning-2-style strip headers, emulated in software. Every horizontal strip of pixels
// is preceded by a two-pixel (64-bit) header naming its destination; a router needs no
// side channel. Header layout (bytes, little-endian): x:u16, y:u16, width:u16,
// display:u8, check:u8 (xor of the other seven bytes ^ 0xA5), packed into two RGBA8 pixels.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "common/image.h"

namespace tessera {

struct StripHeader {
  uint16_t x = 0, y = 0, width = 0;
  uint8_t display = 0;
  bool operator==(const StripHeader&) const = default;
};
inline constexpr int kStripHeaderPixels = 2;

// The most bytes one sender's strip stream for a width x height frame can hold: every pixel
// once, each in a strip of its own (12 bytes a pixel). A sort-first compositor sends a strip
// per tile row, so a frame row crossing T tiles carries T headers: one header a row is no bound.
inline size_t maxStripStreamBytes(int width, int height) {
  return size_t(4) * (1 + kStripHeaderPixels) * size_t(width > 0 ? width : 0) * size_t(height > 0 ? height : 0);
}

void packHeader(const StripHeader& h, uint8_t out[8]);
// False if the check byte does not match.
bool unpackHeader(const uint8_t in[8], StripHeader& h);

// Encodes rect `r` of `img` (rgba8) as one strip per row; rows whose pixels are all
// transparent are left out. Output is a sequence of [header][width pixels].
std::vector<uint8_t> encodeStrips(const Image8& img, const Rect& r, uint8_t display);
// The length of every strip when all strips of the stream are one width (as encodeStrips
// makes them), else 0: what the wire's strip filter needs (row_filter.h).
size_t uniformStripBytes(std::span<const uint8_t> stream);

struct RouteStats {
  int strips_written = 0;
  int strips_rejected = 0;  // bad check, other display id, or would land outside dst
  bool truncated = false;   // stream ended inside a header or strip
  uint64_t pixels_written = 0;
  bool operator==(const RouteStats&) const = default;
};
// Routes strips into dst by their headers alone. Never writes outside dst, never throws.
RouteStats routeStrips(std::span<const uint8_t> stream, Image8& dst, uint8_t display);
// The same, rejecting strips outside `within` too (the part of the image their sender owns).
RouteStats routeStrips(std::span<const uint8_t> stream, Image8& dst, uint8_t display, const Rect& within);

// Sort-first packing: a renderer with several tiles lays them out in its framebuffer
// left to right, top to bottom, with two-pixel gaps for the headers.
struct PackedTile {
  Rect dst;       // where the tile belongs in the display image
  int fb_x, fb_y; // where its first pixel sits in the renderer's framebuffer (after the header)
};
struct TilePacking {
  int fb_width = 0, fb_height = 0;
  std::vector<PackedTile> tiles;
};
TilePacking packTiles(const std::vector<Rect>& tiles, int max_fb_width);
// Writes headers for every row of every tile into the framebuffer's gap pixels.
void writeTileHeaders(const TilePacking& p, Image8& fb, uint8_t display);
// Routes a packed framebuffer with no side information: each framebuffer row is scanned
// from x = 0 as [header][strip][header][strip]...; a header whose check fails ends the row.
// With `allowed` (the sender's own tiles), a strip outside all of them is rejected: one
// renderer cannot overwrite another's tiles.
RouteStats routeFramebuffer(const Image8& fb, Image8& dst, uint8_t display, std::span<const Rect> allowed = {});

}  // namespace tessera
