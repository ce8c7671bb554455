#include "over.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/pixels.h"

namespace tessera::compositor {

uint64_t compositeRegion(const Rect& region, const std::vector<int>& order, const std::vector<proto::Piece>& pieces,
                         ImageF& scratch, Image8& out) {
  if (scratch.width != region.w || scratch.height != region.h) scratch = ImageF(region.w, region.h);
  else std::fill(scratch.px.begin(), scratch.px.end(), 0.0f);
  for (int b : order) {
    const proto::Piece& p = pieces[b];
    if (!p.active.empty()) compositeUnder(scratch, region, p.pixels, p.active, p.format);
  }
  // Quantize once, at the end, so only one rounding reaches the image.
  uint64_t active = 0;
  for (int y = 0; y < region.h; ++y) {
    const float* s = scratch.at(0, y);
    uint8_t* d = out.at(region.x, region.y + y);
    for (int i = 0; i < region.w * 4; ++i) d[i] = (uint8_t)(std::clamp(s[i], 0.0f, 1.0f) * 255.0f + 0.5f);
    for (int x = 0; x < region.w; ++x) active += d[4 * x + 3] != 0;
  }
  return active;
}

}  // namespace tessera::compositor
