// Tiny built-in 5x7 bitmap font (ASCII 32..126) for the on-screen status line; no SDL_ttf.
// Glyph cells are 6x8 pixels (1 px spacing); units are pixels before `scale`. Pure functions.
#pragma once
#include <array>
#include <cstdint>
#include <string_view>

#include "common/image.h"

namespace tessera::display {

inline constexpr int kGlyphW = 5, kGlyphH = 7;  // ink box
inline constexpr int kCellW = 6, kCellH = 8;    // advance and line height

// True if glyph `c` has ink at (x, y), 0 <= x < kGlyphW, 0 <= y < kGlyphH (y down).
// Characters outside 32..126 draw as '?'; coordinates outside the box are false.
bool glyphPixel(char c, int x, int y);

// Width in pixels of `text` drawn at `scale` (scale x kCellW per character).
int textWidth(std::string_view text, int scale = 1);

// Draws `text` with its top-left at (x, y), each font pixel a scale x scale block, into
// premultiplied rgba8 `img`, writing `color` (premultiplied) over ink pixels. Clips at the
// image edges; returns the x just past the last character.
int drawText(Image8& img, int x, int y, std::string_view text, std::array<uint8_t, 4> color,
             int scale = 1);

}  // namespace tessera::display
