#include "master/balance.h"

#include <gtest/gtest.h>

namespace tessera::master {
namespace {

void expectTiling(const std::vector<Rect>& bands, int w, int h) {
  int y = 0;
  for (const Rect& b : bands) {
    EXPECT_EQ(b.x, 0);
    EXPECT_EQ(b.w, w);
    EXPECT_EQ(b.y, y);
    EXPECT_GE(b.h, 1);
    y += b.h;
  }
  EXPECT_EQ(y, h);
}

TEST(Balance, BandsTileTheImage) {
  for (int m : {1, 2, 3, 7}) expectTiling(balancedBands(97, 83, m, {}), 97, 83);
  expectTiling(balancedBands(5, 3, 8, {}), 5, 3);  // more compositors than rows: capped
  EXPECT_EQ(balancedBands(5, 3, 8, {}).size(), 3u);
}

TEST(Balance, EqualActivePixelsPerBand) {
  // All activity in the bottom quarter: two bands should split that quarter, not the image.
  std::vector<Rect> active = {{0, 300, 400, 100}};
  auto bands = balancedBands(400, 400, 2, active);
  expectTiling(bands, 400, 400);
  ASSERT_EQ(bands.size(), 2u);
  EXPECT_NEAR(bands[0].h, 350, 2);  // cut through the middle of the active rows
  std::vector<double> work;
  for (const Rect& b : bands) work.push_back((double)intersect(b, active[0]).area());
  EXPECT_LT(imbalance(work), 1.05);
  // Without balancing (no activity information) the cut is in the middle of the image.
  EXPECT_EQ(balancedBands(400, 400, 2, {})[0].h, 200);
}

TEST(Balance, ImbalanceIsMaxOverMean) {
  EXPECT_DOUBLE_EQ(imbalance({1, 1, 1}), 1.0);
  EXPECT_DOUBLE_EQ(imbalance({3, 1}), 1.5);
  EXPECT_DOUBLE_EQ(imbalance({}), 1.0);
  EXPECT_DOUBLE_EQ(imbalance({0, 0}), 1.0);
}

}  // namespace
}  // namespace tessera::master
