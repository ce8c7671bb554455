#include "common/max_intensity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace tessera {

TransferFunction mirrored(const TransferFunction& tf) {
  std::vector<TfPoint> pts(tf.points().rbegin(), tf.points().rend());
  for (TfPoint& p : pts) p.s = 1 - p.s;
  return TransferFunction(std::move(pts));
}

MaxIntensity::MaxIntensity(const TransferFunction& tf, bool minimum) : tf_(minimum ? mirrored(tf) : tf) {
  const auto& pts = tf_.points();
  const double top = tf_.maxAlpha(0, 1);
  if (!(top > 0)) {
    floor_ = std::numeric_limits<double>::infinity();
    floor_q_ = std::numeric_limits<uint32_t>::max();
    return;
  }
  alpha_scale_ = 1 / top;
  // Opacity is 0 up to the first point with some, or up to the point before it (a ramp up).
  size_t i = 0;
  while (pts[i].a <= 0) ++i;  // top > 0: some point has opacity
  floor_ = i == 0 ? 0 : pts[i - 1].s;
  floor_q_ = (uint32_t)std::floor(floor_ * 65535.0);  // rounding down keeps every value above floor_
}

void MaxIntensity::map(float* px, size_t pixels) const {
  for (size_t p = 0; p < pixels; ++p, px += 4) {
    if (!(px[3] > 0)) continue;
    const auto c = tf_.eval(px[0]);
    const double a = std::clamp(c[3] * alpha_scale_, 0.0, 1.0);
    for (int ch = 0; ch < 3; ++ch) px[ch] = (float)(std::clamp(c[ch], 0.0, 1.0) * a);
    px[3] = (float)a;
  }
}

void compositeMaximum(ImageF& dst, const ImageF& src, const Rect& r) {
  if (dst.width != src.width || dst.height != src.height) throw std::invalid_argument("compositeMaximum: image sizes differ");
  const Rect c = intersect(r, {0, 0, dst.width, dst.height});
  for (int y = c.y; y < c.y + c.h; ++y) {
    float* d = dst.at(c.x, y);
    const float* s = src.at(c.x, y);
    for (int i = 0; i < 4 * c.w; ++i) d[i] = std::max(d[i], s[i]);
  }
}

}  // namespace tessera
