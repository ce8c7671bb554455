// Load balance for sort-last compositing: split the screen into horizontal bands so that
// every compositor gets about the same number of active pixels, estimated from the
// renderers' active rectangles of the previous frame.
#pragma once
#include <vector>

#include "common/image.h"

namespace tessera::master {

// `m` bands (m capped to height) covering [0,width) x [0,height) exactly, top to bottom.
// With no active pixels the bands are equal.
std::vector<Rect> balancedBands(int width, int height, int m, const std::vector<Rect>& active);

// max / mean of `work` (1 when all zero or empty): the imbalance the metrics report.
double imbalance(const std::vector<double>& work);

}  // namespace tessera::master
