// k-d brick splits (exact cover, balance by non-empty voxels) and front-to-back brick order.
#include "common/bricks.h"

#include <gtest/gtest.h>

#include <algorithm>

using namespace tessera;

namespace {
Volume box(int nx, int ny, int nz, float fill = 0.0f) {
  Volume v;
  v.dims = {nx, ny, nz};
  v.values.assign(v.voxelCount(), fill);
  return v;
}
const TransferFunction kStep({{0.0, 0, 0, 0, 0}, {0.5, 0, 0, 0, 0}, {0.5, 1, 1, 1, 1}, {1.0, 1, 1, 1, 1}});
}  // namespace

TEST(Bricks, SplitsCoverTheVolumeExactlyOnce) {
  Volume v = generateVolume({"hollow-shell", 12, 1, {1, 1, 1}});
  v.dims = {12, 12, 12};
  for (int n : {1, 2, 3, 5, 8}) {
    for (const TransferFunction* tf : {(const TransferFunction*)nullptr, &kStep}) {
      BrickTree t = splitBricks(v, n, tf);
      ASSERT_EQ((int)t.bricks.size(), n);
      std::vector<int> hits(v.voxelCount(), 0);
      for (const BrickBox& b : t.bricks) {
        for (int a = 0; a < 3; ++a) ASSERT_LT(b.lo[a], b.hi[a]) << "empty brick, n=" << n;
        for (int z = b.lo[2]; z < b.hi[2]; ++z)
          for (int y = b.lo[1]; y < b.hi[1]; ++y)
            for (int x = b.lo[0]; x < b.hi[0]; ++x) hits[v.index(x, y, z)]++;
      }
      EXPECT_TRUE(std::all_of(hits.begin(), hits.end(), [](int h) { return h == 1; })) << "n=" << n;
    }
  }
}

TEST(Bricks, MoreBricksThanVoxelsIsCapped) {
  Volume v = box(2, 1, 1);
  EXPECT_EQ(splitBricks(v, 5).bricks.size(), 2u);
  EXPECT_THROW(splitBricks(v, 0), std::invalid_argument);
}

TEST(Bricks, BalancesNonEmptyVoxels) {
  Volume v = box(16, 4, 4);  // x is the longest axis
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 6; ++x) v.values[v.index(x, y, z)] = 1.0f;  // visible only in x < 6
  BrickTree two = splitBricks(v, 2, &kStep);
  EXPECT_EQ(two.nodes[0].axis, 0);
  EXPECT_EQ(two.nodes[0].split, 3);  // half of the visible voxels on each side
  BrickTree three = splitBricks(v, 3, &kStep);
  EXPECT_EQ(three.nodes[0].split, 2);  // 1 : 2 bricks -> a third of the visible voxels on the left
  // Without a transfer function (or with nothing visible) the split balances plain volume.
  EXPECT_EQ(splitBricks(v, 2).nodes[0].split, 8);
  EXPECT_EQ(splitBricks(box(16, 4, 4), 2, &kStep).nodes[0].split, 8);
}

// Of equally long axes the one slowest in memory and in the file is cut: z, then y. Two
// bricks of a cube are then two contiguous slabs of the file.
TEST(Bricks, EqualAxesAreCutSlowestFirst) {
  const BrickTree two = splitBricks(box(8, 8, 8), 2);
  EXPECT_EQ(two.nodes[0].axis, 2);
  EXPECT_EQ(two.bricks[0].hi, (std::array<int, 3>{8, 8, 4}));
  const BrickTree four = splitBricks(box(8, 8, 8), 4);
  EXPECT_EQ(four.nodes[four.nodes[0].left].axis, 1) << "the halves are 8x8x4: y before x";
  EXPECT_EQ(splitBricks(box(8, 8, 4), 2).nodes[0].axis, 1);
  EXPECT_EQ(splitBricks(box(9, 8, 8), 2).nodes[0].axis, 0) << "a longer axis still wins";
}

TEST(Bricks, VisibilityOrderPutsTheEyeSideFirst) {
  Volume v = box(10, 14, 6);
  v.spacing = {1, 0.5, 2};
  const Vec3 lo = v.boxMin(), hi = v.boxMax();
  for (int n : {2, 3, 5, 8}) {
    BrickTree t = splitBricks(v, n);
    const Camera cams[] = {
        {{0.1, 0.2, 3}, {0, 0, 0}, {0, 1, 0}, 30, false, 1},
        {{-2, 0.7, -1}, {0, 0, 0}, {0, 1, 0}, 30, false, 1},
        {{0.01, -0.02, 0.03}, {1, 1, 1}, {0, 1, 0}, 60, false, 1},  // eye inside the volume
        {{3, -3, 2}, {0, 0, 0}, {0, 0, 1}, 30, true, 2},
        {{-1, 2, -3}, {0, 0, 0}, {1, 0, 0}, 30, true, 2},
    };
    for (const Camera& cam : cams) {
      std::vector<int> order = t.visibilityOrder(v, cam);
      ASSERT_EQ(order.size(), t.bricks.size());
      std::vector<int> rank(order.size(), -1);
      for (size_t i = 0; i < order.size(); ++i) rank[order[i]] = (int)i;
      ASSERT_TRUE(std::none_of(rank.begin(), rank.end(), [](int r) { return r < 0; }));
      int checked = 0;
      for (size_t i = 0; i < t.bricks.size(); ++i)
        for (size_t j = 0; j < t.bricks.size(); ++j)
          for (int a = 0; a < 3; ++a) {
            const BrickBox &A = t.bricks[i], &B = t.bricks[j];
            if (A.hi[a] != B.lo[a]) continue;
            bool touch = true;  // faces overlap with positive area
            for (int b = 0; b < 3; ++b)
              if (b != a) touch = touch && std::max(A.lo[b], B.lo[b]) < std::min(A.hi[b], B.hi[b]);
            if (!touch) continue;
            double plane = lo[a] + (hi[a] - lo[a]) * A.hi[a] / v.dims[a];
            bool a_first = cam.orthographic ? (cam.target - cam.eye)[a] > 0 : cam.eye[a] < plane;
            EXPECT_EQ(rank[i] < rank[j], a_first) << "n=" << n << " axis " << a << " bricks " << i << "," << j;
            ++checked;
          }
      EXPECT_GE(checked, n - 1);
    }
  }
}
