#include "compositor/over.h"

#include <algorithm>

#include "common/wire/pixels.h"

namespace tessera::compositor {

uint64_t compositeRegion(const Rect& region, const std::vector<int>& order, const std::vector<proto::Piece>& pieces,
                         std::vector<float>& row, Image8& out, const MaxIntensity* mip) {
  row.resize(4 * (size_t)region.w);
  uint64_t active = 0;
  for (int y = region.y; y < region.y + region.h; ++y) {
    std::fill(row.begin(), row.end(), 0.0f);
    for (int b : order) {
      const proto::Piece& p = pieces[b];
      if (y < p.active.y || y >= p.active.y + p.active.h) continue;
      if (mip) compositeMaximumRow(row.data(), region.x, p.pixels, p.active, y - p.active.y, p.format);
      else compositeUnderRow(row.data(), region.x, p.pixels, p.active, y - p.active.y, p.format);
    }
    if (mip) mip->map(row.data(), (size_t)region.w);
    // Quantize once, at the end, so only one rounding reaches the image.
    uint8_t* d = out.at(region.x, y);
    quantizeToUnorm8(row.data(), d, row.size());
    for (int x = 0; x < region.w; ++x) active += d[4 * x + 3] != 0;
  }
  return active;
}

}  // namespace tessera::compositor
