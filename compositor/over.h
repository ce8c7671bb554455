// Sort-last "over" compositing of one region: pieces in front-to-back brick order.
#pragma once
#include <vector>

#include "common/image.h"
#include "common/wire/protocol.h"

namespace tessera::compositor {

// Composites `pieces` (indexed by brick) in `order`, row by row in a cache-resident float
// row, and quantizes each row once into `out` (full image size) at the region's place.
// Returns the number of pixels with alpha > 0 in the region.
uint64_t compositeRegion(const Rect& region, const std::vector<int>& order, const std::vector<proto::Piece>& pieces,
                         std::vector<float>& row, Image8& out);

}  // namespace tessera::compositor
