// Packing a rectangle of a float image into wire pixels (rgba8 rounded to nearest,
// rgba16f round-to-nearest-even as two byte planes, rgba32f exact) and compositing wire pixels "over" a
// float image front to back. Pure functions; thread-safe.
#pragma once
#include <cstddef>
#include <span>
#include <vector>

#include "common/image.h"
#include "common/wire/protocol.h"

namespace tessera {

std::vector<std::byte> packPixels(const ImageF& img, const Rect& r, proto::PixelFormat f);
// The same into `out`, resized (a kept buffer saves zero-filling and faulting in its pages).
void packPixels(const ImageF& img, const Rect& r, proto::PixelFormat f, std::vector<std::byte>& out);
// dst (covering screen rect dst_rect) += (1 - dst.a) * src, where src holds `src_rect`
// (inside dst_rect) in format f. Sizes must already be validated (decodePiece does).
void compositeUnder(ImageF& dst, const Rect& dst_rect, std::span<const std::byte> src, const Rect& src_rect,
                    proto::PixelFormat f);

// The same for one row: `row` (0-based) of the piece goes under `dst_row`, which holds a
// row of the image starting at screen x = dst_x. Lets a compositor work row by row in cache.
void compositeUnderRow(float* dst_row, int dst_x, std::span<const std::byte> src, const Rect& src_rect, int row,
                       proto::PixelFormat f);

// The same for value pixels of a maximum intensity projection (common/max_intensity.h):
// dst = max(dst, src) per channel, in any order of the pieces.
void compositeMaximumRow(float* dst_row, int dst_x, std::span<const std::byte> src, const Rect& src_rect, int row,
                         proto::PixelFormat f);
void compositeMaximum(ImageF& dst, const Rect& dst_rect, std::span<const std::byte> src, const Rect& src_rect,
                      proto::PixelFormat f);

uint16_t floatToHalf(float f);
float halfToFloat(uint16_t h);

}  // namespace tessera
