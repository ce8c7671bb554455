// Min-max hierarchy: block ranges include the trilinear apron, a block is empty iff the
// transfer function has zero opacity over its range, coarser levels and the directional
// distance maps are exact.
#include "renderer/volume/minmax.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "renderer/volume/tf_table.h"

namespace tessera::renderer {
namespace {

Volume randomVolume(std::array<int, 3> dims, uint32_t seed, double zero_fraction) {
  Volume v;
  v.dims = dims;
  v.values.resize(v.voxelCount());
  for (float& x : v.values) {
    seed = seed * 1664525u + 1013904223u;
    const double r = (seed >> 8) / 16777216.0;
    x = r < zero_fraction ? 0.0f : (float)((r - zero_fraction) / (1 - zero_fraction));
  }
  return v;
}

TEST(MinMax, BlockRangesIncludeTheApron) {
  const Volume v = randomVolume({20, 17, 9}, 3, 0.0);
  const MinMaxHierarchy h(v);
  const auto d = h.dims(0);
  ASSERT_EQ(d, (std::array<int, 3>{3, 2, 1}));  // i in [0, n-2] -> (n-2)/8 + 1 blocks
  for (int bz = 0; bz < d[2]; ++bz)
    for (int by = 0; by < d[1]; ++by)
      for (int bx = 0; bx < d[0]; ++bx) {
        float mn = 2, mx = -1;
        for (int z = 8 * bz; z <= std::min(8 * bz + 8, v.dims[2] - 1); ++z)
          for (int y = 8 * by; y <= std::min(8 * by + 8, v.dims[1] - 1); ++y)
            for (int x = 8 * bx; x <= std::min(8 * bx + 8, v.dims[0] - 1); ++x) {
              mn = std::min(mn, v.at(x, y, z));
              mx = std::max(mx, v.at(x, y, z));
            }
        EXPECT_EQ(h.minValue(0, bx, by, bz), mn);
        EXPECT_EQ(h.maxValue(0, bx, by, bz), mx);
      }
  EXPECT_EQ(h.dims(h.levels() - 1), (std::array<int, 3>{1, 1, 1}));
}

TEST(MinMax, EmptyIffZeroOpacityOverTheRange) {
  // Random values in x < 20, a faint 0.2 haze in 20 <= x < 30, zero beyond; the TF is
  // transparent below 0.3, so haze-only and zero blocks are empty and the others are not.
  Volume v = randomVolume({50, 33, 27}, 11, 0.0);
  for (int z = 0; z < 27; ++z)
    for (int y = 0; y < 33; ++y)
      for (int x = 20; x < 50; ++x) v.values[v.index(x, y, z)] = x < 30 ? 0.2f : 0.0f;
  const TransferFunction tf({{0, 0, 0, 0, 0}, {0.3, 1, 1, 1, 0}, {1, 1, 1, 1, 0.8}});
  const MinMaxHierarchy h(v);
  const auto e = h.classify([&](float lo, float hi) { return tf.maxAlpha(lo, hi) == 0; });
  const auto d0 = h.dims(0);
  uint64_t empties = 0;
  for (int z = 0; z < d0[2]; ++z)
    for (int y = 0; y < d0[1]; ++y)
      for (int x = 0; x < d0[0]; ++x) {
        const bool expected = tf.maxAlpha(h.minValue(0, x, y, z), h.maxValue(0, x, y, z)) == 0;
        EXPECT_EQ(e.empty[0][h.index(0, x, y, z)] != 0, expected);
        empties += expected;
      }
  EXPECT_EQ(e.empty_blocks, empties);
  EXPECT_GT(empties, 0u);
  EXPECT_LT(empties, (uint64_t)d0[0] * d0[1] * d0[2]);
  // A coarser node is empty iff all its children are.
  for (int l = 1; l < h.levels(); ++l) {
    const auto dc = h.dims(l), df = h.dims(l - 1);
    for (int z = 0; z < dc[2]; ++z)
      for (int y = 0; y < dc[1]; ++y)
        for (int x = 0; x < dc[0]; ++x) {
          bool all = true;
          for (int c = 0; c < 8; ++c) {
            const int X = 2 * x + (c & 1), Y = 2 * y + ((c >> 1) & 1), Z = 2 * z + (c >> 2);
            if (X < df[0] && Y < df[1] && Z < df[2]) all = all && e.empty[l - 1][h.index(l - 1, X, Y, Z)];
          }
          EXPECT_EQ(e.empty[l][h.index(l, x, y, z)] != 0, all) << "level " << l;
        }
  }
}

TEST(MinMax, OctantDistanceMapsAreExact) {
  Volume v = randomVolume({70, 50, 41}, 5, 0.99997);  // a handful of non-zero voxels
  const MinMaxHierarchy h(v);
  const auto e = h.classify([](float, float hi) { return hi == 0; });
  const auto d = h.dims(0);
  auto empty = [&](int x, int y, int z) { return e.empty[0][h.index(0, x, y, z)] != 0; };
  int nonempty = 0, interesting = 0;  // the case must have matter and mid-range distances
  for (uint8_t f : e.empty[0]) nonempty += !f;
  for (int o = 0; o < 8; ++o) {
    const int s[3] = {(o & 1) ? -1 : 1, (o & 2) ? -1 : 1, (o & 4) ? -1 : 1};
    for (int z = 0; z < d[2]; ++z)
      for (int y = 0; y < d[1]; ++y)
        for (int x = 0; x < d[0]; ++x) {
          // Brute force: largest r whose forward r^3 cube (clipped to the grid) is empty.
          int r = 0;
          for (bool ok = true; ok && r < 255;) {
            for (int k = 0; k <= r && ok; ++k)
              for (int j = 0; j <= r && ok; ++j)
                for (int i = 0; i <= r && ok; ++i) {
                  if (std::max({i, j, k}) != r) continue;  // only the new shell of the cube
                  const int X = x + s[0] * i, Y = y + s[1] * j, Z = z + s[2] * k;
                  if (X < 0 || Y < 0 || Z < 0 || X >= d[0] || Y >= d[1] || Z >= d[2]) continue;
                  ok = empty(X, Y, Z);
                }
            if (ok) ++r;
            if (r > d[0] + d[1] + d[2]) break;  // the whole forward grid is empty
          }
          const int got = e.octant_distance[o][h.index(0, x, y, z)];
          interesting += got >= 2 && got <= 4;
          if (r > d[0] + d[1] + d[2]) EXPECT_GE(got, std::max({d[0], d[1], d[2]}));
          else EXPECT_EQ(got, r) << "octant " << o << " block " << x << "," << y << "," << z;
        }
  }
  EXPECT_GT(nonempty, 0);
  EXPECT_GT(interesting, 50);
}

TEST(TfTableRange, EmptinessIsConservativeForTheTable) {
  // Alpha is 0 up to 0.3: a range ending well below is empty; within two table entries of
  // 0.3 it is not (the table interpolates across neighbouring entries).
  const TransferFunction tf({{0, 0, 0, 0, 0}, {0.3, 1, 1, 1, 0}, {0.5, 1, 1, 1, 0.5}});
  EXPECT_TRUE(TfTable::rangeIsEmpty(tf, 0.0f, 0.299f));
  EXPECT_FALSE(TfTable::rangeIsEmpty(tf, 0.0f, 0.2999f));
  EXPECT_FALSE(TfTable::rangeIsEmpty(tf, 0.1f, 0.4f));
  // And every table lookup in an "empty" range gives exactly zero.
  const TfTable tab(tf, kL0);
  for (int i = 0; i <= 2990; ++i) {
    float out[4];
    tab.lookup(i * 1e-4f, out);
    ASSERT_EQ(out[3], 0.0f) << i;
  }
}

}  // namespace
}  // namespace tessera::renderer
