// Binary swap's geometry (renderer/swap_plan.h), generalised as radix-k: which renderers
// share a round, which rows each keeps, sends and finishes. One rule for the renderers'
// rounds and the display's bands; pure functions.
#pragma once
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "common/wire/protocol.h"

namespace tessera::proto {

// The rounds' group sizes for `places` renderers: its prime factors, smallest first (a power
// of two: binary swap, pairs in every round; 3: one round of three; 6: pairs, then threes).
// Place q's digits in this mixed radix (q = d0 + k0 (d1 + k1 (d2 ...))) say its groups: in
// round j it shares the round with the places that differ from it in digit j alone.
std::vector<size_t> swapRadices(size_t places);
// Part `i` of `k` row bands of `part` (band 0 on top; sizes differ by one row at most).
Rect swapPart(const Rect& part, size_t k, size_t i);
// The rows `place` holds finished after the last round of a width x height frame.
Rect swapFinal(size_t place, size_t places, int width, int height);
// A swap frame's rows that renderer `me` finishes and sends the display (places in the
// visibility order); nullopt without a swap plan or a brick of `me`, or when its band has no
// rows (an image of fewer rows than bands): then it sends the display nothing and the display
// expects nothing.
std::optional<Rect> swapBand(const FrameParams& p, uint32_t me);

}  // namespace tessera::proto
