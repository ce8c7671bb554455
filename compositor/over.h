// Sort-last "over" compositing of one region: pieces in front-to-back brick order.
#pragma once
#include <vector>

#include "common/image.h"
#include "common/max_intensity.h"
#include "common/wire/protocol.h"

namespace tessera::compositor {

// Composites `pieces` (indexed by brick) in `order`, row by row in a cache-resident float
// row, and quantizes each row once into `out` (full image size) at the region's place.
// Returns the number of pixels with alpha > 0 in the region. `mip` (blend: maximum or minimum): the pieces
// are value pixels, merged by their maxima and mapped by it before the row is quantized.
uint64_t compositeRegion(const Rect& region, const std::vector<int>& order, const std::vector<proto::Piece>& pieces,
                         std::vector<float>& row, Image8& out, const MaxIntensity* mip = nullptr);

}  // namespace tessera::compositor
