#include "common/wire/pixels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace tessera {
namespace {

using proto::PixelFormat;

ImageF randomPremultiplied(int w, int h, uint32_t seed) {
  ImageF img(w, h);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float* p = img.at(x, y);
      p[3] = u(rng) < 0.2f ? 0.0f : u(rng);
      for (int c = 0; c < 3; ++c) p[c] = p[3] * u(rng);
    }
  return img;
}

TEST(Half, MatchesIeeeBinary16OnKnownValues) {
  EXPECT_EQ(floatToHalf(0.0f), 0x0000);
  EXPECT_EQ(floatToHalf(1.0f), 0x3C00);
  EXPECT_EQ(floatToHalf(-2.0f), 0xC000);
  EXPECT_EQ(floatToHalf(65504.0f), 0x7BFF);
  EXPECT_EQ(floatToHalf(1e6f), 0x7C00);                    // overflow to +inf
  EXPECT_EQ(floatToHalf(std::ldexp(1.0f, -24)), 0x0001);  // smallest subnormal
  EXPECT_EQ(floatToHalf(1.0f + std::ldexp(1.0f, -11)), 0x3C00);  // tie rounds to even
  EXPECT_TRUE(std::isnan(halfToFloat(floatToHalf(NAN))));
}

TEST(Half, RoundTripIsWithinHalfAnUlpOverTheUnitInterval) {
  for (int i = 0; i <= 100000; ++i) {
    float v = i / 100000.0f;
    float r = halfToFloat(floatToHalf(v));
    // Half has an 11-bit significand: relative error <= 2^-11 (and absolute 2^-25 near 0).
    EXPECT_LE(std::fabs(r - v), std::max(std::ldexp(v, -11), std::ldexp(1.0f, -25))) << v;
  }
}

class PackComposite : public ::testing::TestWithParam<PixelFormat> {};

// Packing a rectangle and compositing it under an empty buffer gives the packed values
// back, to the format's precision.
TEST_P(PackComposite, RoundTripThroughWirePixels) {
  const PixelFormat f = GetParam();
  ImageF img = randomPremultiplied(37, 23, 5);
  Rect r{3, 4, 29, 17};
  auto bytes = packPixels(img, r, f);
  ASSERT_EQ(bytes.size(), (size_t)r.area() * proto::bytesPerPixel(f));
  Rect region{0, 0, 37, 23};
  ImageF dst(37, 23);
  compositeUnder(dst, region, bytes, r, f);
  // rgba8: half a level of rounding; rgba16f: 2^-12 for values <= 1; rgba32f: exact.
  const double tol = f == PixelFormat::RGBA8 ? 0.5 / 255 + 1e-6 : f == PixelFormat::RGBA16F ? std::ldexp(1.0, -12) : 0;
  for (int y = 0; y < 23; ++y)
    for (int x = 0; x < 37; ++x)
      for (int c = 0; c < 4; ++c) {
        bool inside = x >= r.x && x < r.x + r.w && y >= r.y && y < r.y + r.h;
        float want = inside ? img.at(x, y)[c] : 0.0f;
        ASSERT_NEAR(dst.at(x, y)[c], want, tol) << x << "," << y << " c" << c;
      }
}

TEST_P(PackComposite, UnderIsFrontToBackOver) {
  const PixelFormat f = GetParam();
  // Front pixel alpha 0.5 red, back pixel opaque blue: exactly representable in every format.
  ImageF front(1, 1), back(1, 1);
  front.px = {0.5f, 0, 0, 0.5f};
  back.px = {0, 0, 1, 1};
  ImageF dst(1, 1);
  Rect px{0, 0, 1, 1};
  compositeUnder(dst, px, packPixels(front, px, f), px, f);
  compositeUnder(dst, px, packPixels(back, px, f), px, f);
  const double tol = f == PixelFormat::RGBA8 ? 1.0 / 255 : 0;  // 0.5 is not a multiple of 1/255
  EXPECT_NEAR(dst.px[0], 0.5, tol);
  EXPECT_NEAR(dst.px[2], 0.5, tol);
  EXPECT_NEAR(dst.px[3], 1.0, tol);
}

INSTANTIATE_TEST_SUITE_P(Formats, PackComposite,
                         ::testing::Values(PixelFormat::RGBA8, PixelFormat::RGBA16F, PixelFormat::RGBA32F));

TEST(PackPixels, Rgba16fTravelsAsTwoBytePlanes) {
  ImageF img(2, 1);
  img.px = {1.0f, 0.5f, 0, 1.0f, 0, 0, 0, 0};
  auto b = packPixels(img, {0, 0, 2, 1}, PixelFormat::RGBA16F);
  ASSERT_EQ(b.size(), 16u);
  // 1.0 = 0x3C00, 0.5 = 0x3800: low bytes first (all zero), then high bytes.
  for (int i = 0; i < 8; ++i) EXPECT_EQ((int)b[i], 0) << i;
  EXPECT_EQ((int)b[8], 0x3C);
  EXPECT_EQ((int)b[9], 0x38);
  EXPECT_EQ((int)b[11], 0x3C);
}

}  // namespace
}  // namespace tessera
