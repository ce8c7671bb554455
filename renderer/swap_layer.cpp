#include "renderer/swap_layer.h"

#include <cstring>

#include "common/wire/pixels.h"

namespace tessera::renderer {
namespace {

Rect local(const Rect& r, const Rect& origin) { return {r.x - origin.x, r.y - origin.y, r.w, r.h}; }

}  // namespace

void packView(const LayerView& v, proto::PixelFormat f, std::vector<std::byte>& out) {
  if (v.rect.empty()) return out.clear();
  packPixels(*v.img, local(v.rect, v.covers), f, out);
}

Layer blendLayer(const LayerView& mine, std::span<const std::byte> pixels, const Rect& theirs, proto::PixelFormat f,
                 bool partner_in_front, std::vector<float>&& storage) {
  Layer out;
  out.rect = unite(mine.rect, theirs);
  if (out.rect.empty()) return out;
  out.img = ImageF(out.rect.w, out.rect.h, std::move(storage));
  const Rect at = local(mine.rect, out.rect);
  auto row = [&](int y) { return mine.img->at(mine.rect.x - mine.covers.x, mine.rect.y - mine.covers.y + y); };
  if (!partner_in_front) {  // mine first, theirs under it
    for (int y = 0; y < at.h; ++y) std::memcpy(out.img.at(at.x, at.y + y), row(y), sizeof(float) * 4 * at.w);
    if (!theirs.empty()) compositeUnder(out.img, out.rect, pixels, theirs, f);
    return out;
  }
  if (!theirs.empty()) compositeUnder(out.img, out.rect, pixels, theirs, f);  // onto transparent black: theirs exactly
  for (int y = 0; y < at.h; ++y) {  // then mine under it, as the compositors blend
    float* d = out.img.at(at.x, at.y + y);
    const float* s = row(y);
    for (int x = 0; x < 4 * at.w; x += 4) {
      const float t = 1.0f - d[x + 3];
      for (int c = 0; c < 4; ++c) d[x + c] += t * s[x + c];
    }
  }
  return out;
}

}  // namespace tessera::renderer
