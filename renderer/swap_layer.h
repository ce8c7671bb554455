// The images binary swap moves between rounds (swap_plan.h): a renderer's composited part
// of the screen as premultiplied float RGBA, views of it without copies, and the blend of a
// partner's wire pixels in front of or behind it, as the compositors blend (over.h).
#pragma once
#include <span>
#include <vector>

#include "common/image.h"
#include "common/max_intensity.h"
#include "common/wire/protocol.h"

namespace tessera::renderer {

// Premultiplied float RGBA of screen rectangle `rect` (empty rect: nothing).
struct Layer {
  Rect rect;
  ImageF img;  // rect.w x rect.h
};
// Part of a float image that covers screen rect `covers`, without copying it.
struct LayerView {
  const ImageF* img = nullptr;
  Rect covers;  // the screen rect img holds
  Rect rect;    // the part viewed (inside covers, or empty)
};
inline LayerView viewOf(const Layer& l, const Rect& part) { return {&l.img, l.rect, intersect(l.rect, part)}; }
inline LayerView viewOf(const ImageF& full, const Rect& active, const Rect& part) {
  return {&full, {0, 0, full.width, full.height}, intersect(active, part)};
}

// The viewed pixels as wire pixels.
void packView(const LayerView& v, proto::PixelFormat f, std::vector<std::byte>& out);
// `mine` blended with a partner's pixels of screen rect `theirs` (wire format f): the partner's
// run of bricks in front of or behind this renderer's; with `maximum` (blend: maximum or minimum) value
// pixels merged by their maxima, in either order. `storage`: memory to reuse.
Layer blendLayer(const LayerView& mine, std::span<const std::byte> pixels, const Rect& theirs, proto::PixelFormat f,
                 bool partner_in_front, std::vector<float>&& storage = {}, bool maximum = false);

// A finished band as a Strips stream (and its count of pixels with alpha > 0), quantized once
// as the compositors quantize their regions. `frame8`: scratch of the frame's size, kept by
// the caller (strip headers name screen rows). `mip` (blend: maximum or minimum): the band's value pixels
// are mapped first, in place.
void bandStrips(Layer& band, int width, int height, Image8& frame8, proto::Strips& out, const MaxIntensity* mip = nullptr);

}  // namespace tessera::renderer
