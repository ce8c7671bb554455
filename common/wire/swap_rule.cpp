#include "common/wire/swap_rule.h"

#include <bit>

namespace tessera::proto {

Rect swapHalf(const Rect& part, bool upper) {
  const int top = part.h / 2;
  return upper ? Rect{part.x, part.y, part.w, top} : Rect{part.x, part.y + top, part.w, part.h - top};
}

std::optional<Rect> swapBand(const FrameParams& p, uint32_t me) {
  const SortLastWork* work = p.sortLast();
  if (!work || work->swap.empty()) return std::nullopt;
  size_t place = work->order.size();
  for (size_t i = 0; i < work->order.size(); ++i)
    if (work->bricks[work->order[i]].renderer == me) place = i;
  if (place == work->order.size()) return std::nullopt;
  const auto slot = swapSlot(place, work->order.size());
  if (!slot) return std::nullopt;
  Rect part{0, 0, p.width, p.height};
  for (size_t bit = 1; bit < swapSlots(work->order.size()); bit <<= 1) part = swapHalf(part, (*slot & bit) == 0);
  if (part.empty()) return std::nullopt;  // fewer rows than bands: this renderer finishes none
  return part;
}

size_t swapSlots(size_t places) { return places ? std::bit_floor(places) : 0; }

std::optional<size_t> swapSlot(size_t place, size_t places) {
  const size_t extra = places - swapSlots(places);
  if (place < 2 * extra) return place % 2 ? std::nullopt : std::optional<size_t>(place / 2);
  return place - extra;
}

size_t swapPlaceOf(size_t slot, size_t places) {
  const size_t extra = places - swapSlots(places);
  return slot < extra ? 2 * slot : slot + extra;
}

}  // namespace tessera::proto
