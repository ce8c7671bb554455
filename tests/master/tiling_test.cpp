#include "master/tiling.h"

#include <gtest/gtest.h>

#include <numeric>

#include "master/balance.h"

namespace tessera::master {
namespace {

// Tiles cover the image exactly once.
void expectPartition(const std::vector<Rect>& tiles, int w, int h) {
  std::vector<int> hits((size_t)w * h, 0);
  for (const Rect& t : tiles) {
    ASSERT_FALSE(t.empty());
    for (int y = t.y; y < t.y + t.h; ++y)
      for (int x = t.x; x < t.x + t.w; ++x) ++hits[(size_t)y * w + x];
  }
  for (int v : hits) ASSERT_EQ(v, 1);
}

TEST(Tiling, EqualTilesPartitionAnyShape) {
  for (int n : {1, 2, 3, 4, 5, 7, 16}) expectPartition(equalTiles(97, 83, n), 97, 83);
  expectPartition(equalTiles(3, 1, 3), 3, 1);  // one-pixel tiles
  EXPECT_EQ(equalTiles(2, 2, 9).size(), 4u);    // no more tiles than pixels
}

TEST(Tiling, BalancedTilesEqualiseACornerCrowdedCost) {
  const int w = 256, h = 256;
  CostGrid cost(w, h);
  cost.add({0, 0, 64, 64}, 90.0);    // geometry crowds the top-left corner
  cost.add({0, 0, 256, 256}, 10.0);  // a little everywhere
  for (int n : {2, 3, 4}) {
    auto tiles = balancedTiles(w, h, n, cost);
    expectPartition(tiles, w, h);
    std::vector<double> work;
    for (const Rect& t : tiles) work.push_back(cost.cost(t));
    EXPECT_LT(imbalance(work), 1.1) << n << " tiles";
    std::vector<double> equal;
    for (const Rect& t : equalTiles(w, h, n)) equal.push_back(cost.cost(t));
    EXPECT_GT(imbalance(equal), 1.5) << "the equal tiling should be badly balanced here";
  }
}

TEST(Tiling, CostGridConservesCost) {
  CostGrid g(100, 50, 7);
  g.add({10, 5, 33, 20}, 12.0);
  EXPECT_NEAR(g.cost({0, 0, 100, 50}), 12.0, 1e-9);
  EXPECT_TRUE(CostGrid(10, 10).empty());
  expectPartition(balancedTiles(100, 50, 5, CostGrid(100, 50)), 100, 50);
}

}  // namespace
}  // namespace tessera::master
