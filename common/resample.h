// Scaling a frame to the window: bilinear resampling of premultiplied rgba8 (filtering
// premultiplied values is what keeps edges free of dark fringes). The display shows
// reduced interactive frames this way, and the level-of-detail sweep measures their error
// with the same function, so the error it reports is the error the user sees.
#pragma once
#include "common/image.h"

namespace tessera {

// `src` resampled to width x height with pixel centres aligned (a pixel's centre at
// (x + 0.5) * src.width / width - 0.5 in the source) and edges clamped. Same size: a copy.
// Throws std::invalid_argument for an empty source or a non-positive size.
Image8 resizeBilinear(const Image8& src, int width, int height);

}  // namespace tessera
