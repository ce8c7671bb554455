// Rect ops, quantization, "over" compositing and error metrics, checked against exact values.
#include "common/image.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace tessera;

TEST(Rect, IntersectAndUnite) {
  Rect a{0, 0, 10, 10}, b{5, 6, 10, 10};
  EXPECT_EQ(intersect(a, b), (Rect{5, 6, 5, 4}));
  EXPECT_TRUE(intersect(a, Rect{10, 0, 5, 5}).empty());  // touching edges do not overlap
  EXPECT_EQ(unite(a, b), (Rect{0, 0, 15, 16}));
  EXPECT_EQ(unite(Rect{}, b), b);
  EXPECT_EQ(unite(a, Rect{3, 3, 0, 7}), a);
  EXPECT_EQ(Rect{}.area(), 0);
}

TEST(Image, ActiveRegion) {
  ImageF img(7, 5);
  EXPECT_TRUE(activeRegion(img).empty());
  img.at(2, 1)[3] = 0.1f;
  img.at(5, 3)[3] = 1e-30f;  // tiny but non-zero alpha still counts
  img.at(6, 4)[0] = 1.0f;    // colour without alpha does not (premultiplied: cannot happen)
  EXPECT_EQ(activeRegion(img), (Rect{2, 1, 4, 3}));
  Image8 b = toRGBA8(img);
  EXPECT_EQ(activeRegion(b), (Rect{2, 1, 1, 1}));  // 1e-30 rounds to 0
}

TEST(Image, ToRGBA8RoundsToNearestAndClamps) {
  ImageF img(2, 2);
  const float in[16] = {0.0f, 1.0f, -0.5f, 2.0f, 127.49f / 255, 127.51f / 255, 0.5f / 255 - 1e-4f, 0.5f / 255 + 1e-4f,
                        std::numeric_limits<float>::quiet_NaN(), INFINITY, -INFINITY, 254.6f / 255,
                        0, 0, 0, 0};
  std::copy(in, in + 16, img.px.begin());
  Image8 b = toRGBA8(img);
  const uint8_t want[16] = {0, 255, 0, 255, 127, 128, 0, 1, 0, 255, 0, 255, 0, 0, 0, 0};
  for (int i = 0; i < 16; ++i) EXPECT_EQ(b.px[i], want[i]) << "index " << i;
}

TEST(Image, ByteFloatByteRoundTripIsExact) {
  Image8 a(256, 1);
  for (int i = 0; i < 256; ++i) a.px[4 * i] = a.px[4 * i + 1] = a.px[4 * i + 2] = a.px[4 * i + 3] = (uint8_t)i;
  EXPECT_EQ(toRGBA8(toFloat(a)), a);
}

TEST(Image, CompositeOverExact) {
  // Values are dyadic fractions, so float arithmetic is exact and we can compare with ==.
  ImageF dst(3, 2), src(3, 2);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x) {
      float* d = dst.at(x, y);
      float* s = src.at(x, y);
      d[0] = 0.25f, d[1] = 0, d[2] = 0, d[3] = 0.5f;
      s[0] = 0.5f, s[1] = 0.5f, s[2] = 0.125f, s[3] = 1.0f;
    }
  compositeOver(dst, src, Rect{1, 0, 5, 1});  // clipped to the image: pixels (1,0) and (2,0)
  const float* in = dst.at(1, 0);
  EXPECT_EQ(in[0], 0.5f);
  EXPECT_EQ(in[1], 0.25f);
  EXPECT_EQ(in[2], 0.0625f);
  EXPECT_EQ(in[3], 1.0f);
  EXPECT_EQ(dst.at(2, 0)[3], 1.0f);
  EXPECT_EQ(dst.at(0, 0)[3], 0.5f);  // outside the rect: untouched
  EXPECT_EQ(dst.at(1, 1)[0], 0.25f);
  // An opaque destination ignores whatever lies behind it.
  ImageF before = dst;
  compositeOver(dst, src, Rect{1, 0, 1, 1});
  EXPECT_EQ(dst.at(1, 0)[0], before.at(1, 0)[0]);
}

TEST(Image, CompositeOverSizeMismatchThrows) {
  ImageF a(2, 2), b(3, 2);
  EXPECT_THROW(compositeOver(a, b, Rect{0, 0, 2, 2}), std::invalid_argument);
}

TEST(Image, CompareMetrics) {
  ImageF a(1, 1), b(1, 1);
  ImageError e = compare(a, b);
  EXPECT_EQ(e.max_abs, 0);
  EXPECT_TRUE(std::isinf(e.psnr) && e.psnr > 0);
  b.px[2] = 0.1f;
  e = compare(a, b);
  // One channel of four differs by 0.1: mse = 0.01/4, rmse = 0.05, psnr = 10 log10(400).
  EXPECT_NEAR(e.max_abs, 0.1, 1e-7);  // float representation of 0.1
  EXPECT_NEAR(e.rmse, 0.05, 1e-7);
  EXPECT_NEAR(e.psnr, 26.0206, 1e-3);
  Image8 c(2, 1), d(2, 1);
  d.px[7] = 255;
  ImageError e8 = compare(c, d);
  EXPECT_DOUBLE_EQ(e8.max_abs, 1.0);
  EXPECT_NEAR(e8.rmse, std::sqrt(1.0 / 8), 1e-12);
  EXPECT_THROW(compare(ImageF(1, 2), ImageF(2, 1)), std::invalid_argument);
}

namespace tessera {
namespace {

// The one rgba8 quantizer: round to nearest, clamp, NaN -> 0, identical in the SIMD body and
// the scalar tail (19 values: two 8-wide steps and a tail of 3).
TEST(Quantize, RoundsClampsAndZeroesNaNInBodyAndTail) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> in = {0.0f, 1.0f, -1.0f, 2.0f, nan, 0.5f / 255, 0.49f / 255, 128.5f / 255, 254.49f / 255,
                                 1.0f, nan,  -0.f, 0.2f, 0.7f, 1e30f, -1e30f, nan, 0.5f / 255, 2.0f};
  const std::vector<int> want = {0, 255, 0, 255, 0, 1, 0, 129, 254, 255, 0, 0, 51, 179, 255, 0, 0, 1, 255};
  std::vector<uint8_t> out(in.size(), 77);
  quantizeToUnorm8(in.data(), out.data(), in.size());
  for (size_t i = 0; i < in.size(); ++i) EXPECT_EQ(int(out[i]), want[i]) << "value " << i << " = " << in[i];
}

}  // namespace
}  // namespace tessera
