// Frequency-domain anti-aliasing post filter: FFT of each channel, multiply by a Gaussian
// low-pass, inverse FFT (FFTW, single precision). Applied to a whole image; applied per tile it
// differs from the whole-image result near tile borders (the filter reaches across them).
// Not thread-safe: FFTW's planner is global.
#pragma once
#include "common/image.h"

namespace tessera::renderer {

// Gaussian of standard deviation sigma_px (pixels; 0 leaves the image unchanged). Borders are
// extended by edge replication so the FFT's wrap-around does not bleed opposite edges together.
// Keeps the result premultiplied: colour is clamped to alpha. Throws std::invalid_argument for
// sigma_px < 0 or > 64.
void lowPassFilter(Image8& img, double sigma_px);

}  // namespace tessera::renderer
