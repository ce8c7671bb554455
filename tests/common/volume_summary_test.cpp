// The master's view of a volume: a streamed summary that must equal what the whole volume
// says (block value ranges, data range), and brick splits on block faces that cover it.
#include "common/volume_summary.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "tests/common/raw_spec.h"
#include "tests/common/temp_dir.h"

namespace tessera {
namespace {

void expectBlocksOfWhole(const VolumeSummary& s, const Volume& whole) {
  for (int bz = 0; bz < s.blocks[2]; ++bz)
    for (int by = 0; by < s.blocks[1]; ++by)
      for (int bx = 0; bx < s.blocks[0]; ++bx) {
        float lo = 2, hi = -1;
        for (int z = bz * s.edge; z < std::min(whole.dims[2], (bz + 1) * s.edge); ++z)
          for (int y = by * s.edge; y < std::min(whole.dims[1], (by + 1) * s.edge); ++y)
            for (int x = bx * s.edge; x < std::min(whole.dims[0], (bx + 1) * s.edge); ++x)
              lo = std::min(lo, whole.at(x, y, z)), hi = std::max(hi, whole.at(x, y, z));
        const size_t i = bx + (size_t)s.blocks[0] * (by + (size_t)s.blocks[1] * bz);
        ASSERT_EQ(s.lo[i], lo) << bx << "," << by << "," << bz;
        ASSERT_EQ(s.hi[i], hi) << bx << "," << by << "," << bz;
      }
}

TEST(VolumeSummary, AGeneratedVolumeSummaryEqualsTheWholeVolumesBlocks) {
  Scene scene = defaultScene();
  scene.volume = GeneratorSpec{"noise-cloud", 70, 2, {1, 1, 1}};
  const VolumeSummary s = summarizeVolume(scene);
  const Volume whole = loadVolume(scene);
  EXPECT_EQ(s.edge, 8);  // 70 >= 64: every axis has at least 8 blocks
  EXPECT_EQ(s.blocks, (std::array<int, 3>{9, 9, 9}));
  EXPECT_TRUE(s.shape.values.empty()) << "the summary holds no voxels";
  EXPECT_EQ(s.shape.data_range, whole.data_range);
  expectBlocksOfWhole(s, whole);
}

TEST(VolumeSummary, ARawFileWithoutARangeIsSummarisedOverItsOwnValues) {
  test::TempDir t("summary");
  const std::array<int, 3> n{21, 17, 12};
  std::vector<uint16_t> data((size_t)n[0] * n[1] * n[2]);
  for (size_t i = 0; i < data.size(); ++i) data[i] = (uint16_t)(300 + (i * 2654435761u) % 700);
  Scene scene = defaultScene();
  scene.volume = test::rawSpec(t.write("s.raw", data.data(), data.size() * 2), n, VoxelType::UInt16, {1, 1, 1}, false, {0, 0});
  const VolumeSummary s = summarizeVolume(scene);
  const Volume whole = loadVolume(scene);
  EXPECT_EQ(s.edge, 1);  // 12 < 16: blocks of one voxel keep 12 cuts on the shortest axis
  EXPECT_EQ(s.shape.data_range, whole.data_range);
  EXPECT_EQ(s.shape.mapped_range, whole.mapped_range);
  expectBlocksOfWhole(s, whole);
}

// A file without range is read once: the blocks' bounds in its own values, normalised with
// the range found on the way, are the bounds of the values a renderer normalises; a constant
// file maps to 0 as loadVolume maps it.
TEST(VolumeSummary, AFileWithoutARangeIsReadOnceAndNormalisedAsLoadVolumeDoes) {
  test::TempDir t("summary_once");
  const std::array<int, 3> n{40, 36, 33};
  std::vector<float> data((size_t)n[0] * n[1] * n[2]);
  for (size_t i = 0; i < data.size(); ++i) data[i] = -3.7f + 15.8f * (float)((i * 2654435761u) % 100003) / 100003.0f;
  for (bool constant : {false, true}) {
    if (constant) std::fill(data.begin(), data.end(), 2.5f);
    Scene scene = defaultScene();
    scene.volume = test::rawSpec(t.write(constant ? "c.raw" : "f.raw", data.data(), data.size() * 4), n,
                                 VoxelType::Float32, {1, 1, 1}, false, {0, 0});
    const uint64_t before = volumeSamplesRead();
    const VolumeSummary s = summarizeVolume(scene);
    EXPECT_EQ(volumeSamplesRead() - before, data.size() * 4) << "one pass over the file";
    EXPECT_EQ(s.edge, 4);
    Scene fixed = scene;
    fixVolumeRange(fixed);  // what the renderers normalise with
    EXPECT_EQ(s.shape.mapped_range, std::get<RawVolumeSpec>(fixed.volume).range);
    const Volume whole = loadVolume(fixed);
    EXPECT_EQ(s.shape.data_range, (std::array<double, 2>{*std::min_element(data.begin(), data.end()),
                                                         *std::max_element(data.begin(), data.end())}));
    expectBlocksOfWhole(s, whole);
  }
}

TEST(VolumeSummary, BricksAreCutOnBlockFacesAndCoverTheVolumeOnce) {
  Scene scene = defaultScene();
  scene.volume = GeneratorSpec{"hollow-shell", 75, 1, {1, 1, 1}};
  const VolumeSummary s = summarizeVolume(scene);
  for (int n : {1, 2, 3, 4, 7}) {
    const BrickTree tree = splitBricks(s, n, scene.tf);
    ASSERT_EQ((int)tree.bricks.size(), n);
    long long voxels = 0;
    for (const BrickBox& b : tree.bricks)
      for (int a = 0; a < 3; ++a) {
        EXPECT_TRUE(b.lo[a] % s.edge == 0) << "n=" << n << " lo " << b.lo[a];
        EXPECT_TRUE(b.hi[a] % s.edge == 0 || b.hi[a] == 75) << "n=" << n << " hi " << b.hi[a];
        EXPECT_LT(b.lo[a], b.hi[a]);
        if (a == 2) voxels += (long long)(b.hi[0] - b.lo[0]) * (b.hi[1] - b.lo[1]) * (b.hi[2] - b.lo[2]);
      }
    EXPECT_EQ(voxels, 75LL * 75 * 75) << "n=" << n;  // disjoint boxes of a k-d split: sizes add up
  }
}

}  // namespace
}  // namespace tessera
