#include "renderer/swap_layer.h"

#include <cstring>

#include "common/wire/pixels.h"
#include "common/wire/strips.h"

namespace tessera::renderer {
namespace {

Rect local(const Rect& r, const Rect& origin) { return {r.x - origin.x, r.y - origin.y, r.w, r.h}; }

// A w x h image in `storage`'s memory, transparent outside `keep`, whose pixels the caller
// writes next (clearing them too was 0.8% of a 4+2 farm renderer's time, about what the
// blending itself took).
ImageF clearedOutside(int w, int h, std::vector<float>&& storage, const Rect& keep) {
  ImageF img;
  img.width = w, img.height = h;
  img.px = std::move(storage);
  img.px.resize((size_t)w * h * 4);
  img.clear({0, 0, w, keep.y});
  img.clear({0, keep.y + keep.h, w, h - keep.y - keep.h});
  img.clear({0, keep.y, keep.x, keep.h});
  img.clear({keep.x + keep.w, keep.y, w - keep.x - keep.w, keep.h});
  return img;
}

}  // namespace

void packView(const LayerView& v, proto::PixelFormat f, std::vector<std::byte>& out) {
  if (v.rect.empty()) return out.clear();
  packPixels(*v.img, local(v.rect, v.covers), f, out);
}

Layer blendLayer(const LayerView& mine, std::span<const std::byte> pixels, const Rect& theirs, proto::PixelFormat f,
                 bool partner_in_front, std::vector<float>&& storage, bool maximum) {
  Layer out;
  out.rect = unite(mine.rect, theirs);
  if (out.rect.empty()) return out;
  const Rect at = local(mine.rect, out.rect);
  auto row = [&](int y) { return mine.img->at(mine.rect.x - mine.covers.x, mine.rect.y - mine.covers.y + y); };
  if (maximum || !partner_in_front) {  // mine first, theirs under it (or merged: order does not matter)
    out.img = clearedOutside(out.rect.w, out.rect.h, std::move(storage), at);
    for (int y = 0; y < at.h; ++y) std::memcpy(out.img.at(at.x, at.y + y), row(y), sizeof(float) * 4 * at.w);
    if (!theirs.empty()) {
      if (maximum) compositeMaximum(out.img, out.rect, pixels, theirs, f);
      else compositeUnder(out.img, out.rect, pixels, theirs, f);
    }
    return out;
  }
  out.img = ImageF(out.rect.w, out.rect.h, std::move(storage));
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

void bandStrips(Layer& band, int width, int height, Image8& frame8, proto::Strips& out, const MaxIntensity* mip) {
  if (frame8.width != width || frame8.height != height) frame8 = Image8(width, height);
  const Rect& r = band.rect;
  out.active_pixels = 0;
  for (int y = 0; y < r.h; ++y) {
    if (mip) mip->map(band.img.at(0, y), (size_t)r.w);
    uint8_t* row = frame8.at(r.x, r.y + y);
    quantizeToUnorm8(band.img.at(0, y), row, 4 * (size_t)r.w);
    for (int x = 0; x < r.w; ++x) out.active_pixels += row[4 * x + 3] != 0;
  }
  out.stream = encodeStrips(frame8, r, 0);
}

}  // namespace tessera::renderer
