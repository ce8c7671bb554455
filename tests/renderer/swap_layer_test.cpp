// blendLayer (renderer/swap_layer.h) in memory that held another layer: the blend clears only
// what it does not overwrite, and must still equal a blend in fresh memory bit for bit.
#include <gtest/gtest.h>

#include <vector>

#include "common/wire/pixels.h"
#include "renderer/swap_layer.h"

namespace tessera::renderer {
namespace {

ImageF gradient(int w, int h, float tint) {
  ImageF img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float a = 0.1f + 0.8f * float(x + y) / float(w + h);
      float* p = img.at(x, y);
      p[0] = a * tint, p[1] = a * 0.5f, p[2] = a * (1 - tint), p[3] = a;
    }
  return img;
}

TEST(SwapLayer, ABlendInRecycledMemoryEqualsOneInFreshMemory) {
  const ImageF mine_img = gradient(40, 30, 0.9f);
  const ImageF theirs_img = gradient(40, 30, 0.2f);
  // Mine and theirs overlap in part; their union has corners neither covers.
  const Rect mine_rect{4, 2, 20, 12}, theirs_rect{14, 8, 22, 18};
  const LayerView mine = viewOf(mine_img, mine_rect, Rect{0, 0, 40, 30});
  for (auto f : {proto::PixelFormat::RGBA8, proto::PixelFormat::RGBA16F})
    for (bool in_front : {false, true}) {
      const std::vector<std::byte> pixels = packPixels(theirs_img, theirs_rect, f);
      const Layer fresh = blendLayer(mine, pixels, theirs_rect, f, in_front);
      const Layer used = blendLayer(mine, pixels, theirs_rect, f, in_front, std::vector<float>(40 * 30 * 4, 0.75f));
      ASSERT_EQ(fresh.rect, (Rect{4, 2, 32, 24}));
      EXPECT_EQ(used.rect, fresh.rect);
      EXPECT_TRUE(used.img == fresh.img) << "partner in front: " << in_front;
      EXPECT_EQ(fresh.img.at(0, 23)[3], 0.0f) << "a corner neither covers is transparent";
    }
}

}  // namespace
}  // namespace tessera::renderer
