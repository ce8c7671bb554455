#include "common/resample.h"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

namespace tessera {
namespace {

TEST(Resample, SameSizeIsACopyAndAFlatImageStaysFlat) {
  Image8 a(5, 3);
  for (size_t i = 0; i < a.px.size(); ++i) a.px[i] = (uint8_t)(i * 7);
  EXPECT_EQ(resizeBilinear(a, 5, 3).px, a.px);
  Image8 flat(4, 4);
  for (size_t i = 0; i < flat.px.size(); i += 4) flat.px[i] = 10, flat.px[i + 1] = 20, flat.px[i + 2] = 30, flat.px[i + 3] = 40;
  const Image8 big = resizeBilinear(flat, 13, 7);
  for (size_t i = 0; i < big.px.size(); i += 4) {
    ASSERT_EQ(big.px[i], 10);
    ASSERT_EQ(big.px[i + 3], 40);
  }
}

TEST(Resample, DoublingInterpolatesBetweenPixelCentres) {
  // Two pixels 0 and 200: output centres at source 0.25 - 0.5 (clamped to 0), 0.25, 0.75, 1.25
  // (clamped to 1) -> 0, 50, 150, 200.
  Image8 a(2, 1);
  a.px = {0, 0, 0, 0, 200, 200, 200, 200};
  const Image8 b = resizeBilinear(a, 4, 1);
  EXPECT_EQ(b.px[0], 0);
  EXPECT_EQ(b.px[4], 50);
  EXPECT_EQ(b.px[8], 150);
  EXPECT_EQ(b.px[12], 200);
}

TEST(Resample, PremultipliedColourNeverExceedsAlpha) {
  std::mt19937 rng(3);
  Image8 a(17, 11);
  for (size_t i = 0; i < a.px.size(); i += 4) {
    const uint8_t alpha = (uint8_t)(rng() % 256);
    for (int c = 0; c < 3; ++c) a.px[i + c] = (uint8_t)(alpha ? rng() % (alpha + 1) : 0);
    a.px[i + 3] = alpha;
  }
  const Image8 b = resizeBilinear(a, 50, 29);
  for (size_t i = 0; i < b.px.size(); i += 4)
    for (int c = 0; c < 3; ++c) ASSERT_LE(b.px[i + c], b.px[i + 3]) << i;
}

TEST(Resample, BadSizesAreRefused) {
  EXPECT_THROW(resizeBilinear(Image8(), 4, 4), std::invalid_argument);
  EXPECT_THROW(resizeBilinear(Image8(2, 2), 0, 4), std::invalid_argument);
}

}  // namespace
}  // namespace tessera
