// Binary swap's geometry (renderer/swap_plan.h): which rows each renderer keeps, sends and
// finishes. One rule for the renderers' rounds and the display's bands; pure functions.
#pragma once
#include <cstddef>
#include <cstdint>
#include <optional>

#include "common/wire/protocol.h"

namespace tessera::proto {

// A binary swap's split of `part` between two partners: the upper half (the lower place keeps
// it) or the lower one; one rule for the renderers' rounds and the display's bands.
Rect swapHalf(const Rect& part, bool upper);
// Binary swap for any count of places (IceT's folding): with P the largest power of two
// <= places and e = places - P, each odd place among the first 2e first sends its whole image
// to the place before it and is done; then P slots swap in log2 P rounds. Slot s < e is the
// merged pair of places 2s, 2s+1, slot s >= e is place s + e: slots keep the places' order,
// so every blend still joins runs of bricks consecutive front to back.
size_t swapSlots(size_t places);                              // P
std::optional<size_t> swapSlot(size_t place, size_t places);  // nullopt: a place that folds away
size_t swapPlaceOf(size_t slot, size_t places);               // the place that holds slot `slot`
// A binary-swap frame's rows that renderer `me` finishes and sends the display (pairs by places
// in the visibility order: renderer/swap_plan.h); nullopt without a swap plan or a brick of
// `me`, when `me` folds its image into a partner's, or when its band has no rows (an image
// of fewer rows than bands): then it sends the display nothing and the display expects nothing.
std::optional<Rect> swapBand(const FrameParams& p, uint32_t me);

}  // namespace tessera::proto
