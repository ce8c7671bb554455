#include "common/wire/swap_rule.h"

namespace tessera::proto {

std::vector<size_t> swapRadices(size_t places) {
  std::vector<size_t> radices;
  for (size_t f = 2; f * f <= places; ++f)
    while (places % f == 0) radices.push_back(f), places /= f;
  if (places > 1) radices.push_back(places);
  return radices;
}

Rect swapPart(const Rect& part, size_t k, size_t i) {
  const int y0 = (int)((int64_t)part.h * (int64_t)i / (int64_t)k);
  const int y1 = (int)((int64_t)part.h * (int64_t)(i + 1) / (int64_t)k);
  return Rect{part.x, part.y + y0, part.w, y1 - y0};
}

Rect swapFinal(size_t place, size_t places, int width, int height) {
  Rect part{0, 0, width, height};
  for (size_t k : swapRadices(places)) {
    part = swapPart(part, k, place % k);
    place /= k;
  }
  return part;
}

std::optional<Rect> swapBand(const FrameParams& p, uint32_t me) {
  const SortLastWork* work = p.sortLast();
  if (!work || work->swap.empty()) return std::nullopt;
  size_t place = work->order.size();
  for (size_t i = 0; i < work->order.size(); ++i)
    if (work->bricks[work->order[i]].renderer == me) place = i;
  if (place == work->order.size()) return std::nullopt;
  const Rect part = swapFinal(place, work->order.size(), p.width, p.height);
  if (part.empty()) return std::nullopt;  // fewer rows than bands: this renderer finishes none
  return part;
}

}  // namespace tessera::proto
