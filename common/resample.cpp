#include "common/resample.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace tessera {
namespace {

// Per destination column (or row): the two source indices and the weight of the second,
// in 1/256 (8-bit weights keep the inner loop in integers; the rounding error is < 1 level).
struct Tap {
  int i0, i1, w1;
};

std::vector<Tap> taps(int src, int dst) {
  std::vector<Tap> t((size_t)dst);
  const double scale = (double)src / dst;
  for (int d = 0; d < dst; ++d) {
    const double s = std::clamp((d + 0.5) * scale - 0.5, 0.0, (double)(src - 1));
    const int i0 = std::min((int)s, src - 1);
    t[(size_t)d] = {i0, std::min(i0 + 1, src - 1), (int)std::lround((s - i0) * 256)};
  }
  return t;
}

}  // namespace

Image8 resizeBilinear(const Image8& src, int width, int height) {
  if (src.width <= 0 || src.height <= 0) throw std::invalid_argument("resizeBilinear: empty source image");
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("resizeBilinear: size must be positive, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  if (width == src.width && height == src.height) return src;
  const std::vector<Tap> xs = taps(src.width, width), ys = taps(src.height, height);
  Image8 out(width, height);
  std::vector<uint32_t> row((size_t)src.width * 4);  // the vertical blend of one row, x 256
  for (int y = 0; y < height; ++y) {
    const Tap ty = ys[(size_t)y];
    const uint8_t* __restrict r0 = src.px.data() + (size_t)ty.i0 * src.width * 4;
    const uint8_t* __restrict r1 = src.px.data() + (size_t)ty.i1 * src.width * 4;
    uint32_t* __restrict v = row.data();
    for (size_t i = 0; i < row.size(); ++i) v[i] = r0[i] * (uint32_t)(256 - ty.w1) + r1[i] * (uint32_t)ty.w1;
    uint8_t* __restrict o = out.px.data() + (size_t)y * width * 4;
    for (int x = 0; x < width; ++x) {
      const Tap tx = xs[(size_t)x];
      const uint32_t* a = v + tx.i0 * 4;
      const uint32_t* b = v + tx.i1 * 4;
      // Both weights sum to 256: the result is <= 255 * 65536, and premultiplied (colour <=
      // alpha) survives because every channel gets the same weights.
      for (int c = 0; c < 4; ++c) o[x * 4 + c] = (uint8_t)((a[c] * (256 - tx.w1) + b[c] * tx.w1 + 32768) >> 16);
    }
  }
  return out;
}

}  // namespace tessera
