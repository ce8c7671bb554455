// The master's view of a volume: a streamed summary that must equal what the whole volume
// says (block value ranges, data range), and brick splits on block faces that cover it.
#include "common/volume_summary.h"

#include <gtest/gtest.h>

#include <nifti2_io.h>

#include <algorithm>
#include <cstring>
#include <tuple>
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
  EXPECT_EQ(s.edge, 8);  // 9^3 blocks >= 8^3
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
  EXPECT_EQ(s.edge, 2);  // 11 x 9 x 6 blocks of 2: 594 >= 512 (of 4: 90)
  EXPECT_EQ(s.shape.data_range, whole.data_range);
  EXPECT_EQ(s.shape.mapped_range, whole.mapped_range);
  expectBlocksOfWhole(s, whole);
}

// A file without range is read once: the blocks' bounds in its own values, normalised with
// the range found on the way, are the bounds of the values a renderer normalises; a constant
// file maps to 0 as loadVolume maps it.
void expectReadOnceAndNormalisedAsLoadVolume(const Scene& scene, uint64_t sample_bytes, std::array<double, 2> data,
                                             int edge) {
  const uint64_t before = volumeSamplesRead();
  const VolumeSummary s = summarizeVolume(scene);
  EXPECT_EQ(volumeSamplesRead() - before, sample_bytes) << "one pass over the file (its step 0)";
  EXPECT_EQ(s.edge, edge);
  Scene fixed = scene;
  fixVolumeRange(fixed);  // what the renderers normalise with
  EXPECT_EQ(s.shape.mapped_range, std::get<RawVolumeSpec>(fixed.volume).range);
  EXPECT_EQ(s.shape.data_range, data);
  expectBlocksOfWhole(s, loadVolume(fixed));
}

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
    expectReadOnceAndNormalisedAsLoadVolume(
        scene, data.size() * 4,
        {*std::min_element(data.begin(), data.end()), *std::max_element(data.begin(), data.end())}, 4);
  }
}

// The same through nifticlib's files: a gzip stream decoded once with the header's scaling,
// and a 4-D file whose range is its step 0's.
TEST(VolumeSummary, ANiftiFileGzippedScaledOrFourDIsReadOnceToo) {
  test::TempDir t("summary_once_nifti");
  const int nx = 24, ny = 20, nz = 17, nt = 3;
  std::vector<int16_t> v((size_t)nx * ny * nz * nt);
  for (size_t i = 0; i < v.size(); ++i) v[i] = (int16_t)((int)((i * 2654435761u) % 3001) - 1000 + 500 * (int)(i / (v.size() / nt)));
  const size_t step = v.size() / nt;
  for (const auto& [name, steps, slope, inter] :
       {std::tuple{"g.nii.gz", 1, 2.0, -5.0}, std::tuple{"s.nii", 1, 0.5, 7.0}, std::tuple{"t.nii", nt, 0.0, 0.0}}) {
    const int64_t dims[8] = {steps > 1 ? 4 : 3, nx, ny, nz, steps, 1, 1, 1};
    nifti_image* nim = nifti_make_new_nim(dims, DT_INT16, 1);
    ASSERT_NE(nim, nullptr);
    nim->scl_slope = slope, nim->scl_inter = inter;
    std::memcpy(nim->data, v.data(), (size_t)steps * step * 2);
    ASSERT_EQ(nifti_set_filenames(nim, t.file(name).c_str(), 0, 1), 0);
    nifti_image_write(nim);
    nifti_image_free(nim);
    const auto [lo, hi] = std::minmax_element(v.begin(), v.begin() + (std::ptrdiff_t)step);
    const double a = slope == 0 ? 1 : slope;
    const std::array<double, 2> data{(float)(a * *lo + inter), (float)(a * *hi + inter)};
    SCOPED_TRACE(name);
    expectReadOnceAndNormalisedAsLoadVolume(parseScene(std::string("volume: {file: ") + name + "}\n", t.path.string(), "s.yaml"),
                                            step * 2, data, 2);
  }
}

// Read in its own values, a file with a declared range says what its values are.
TEST(VolumeSummary, ValuesReadFromAFileWithADeclaredRangeSayTheirOwnRange) {
  test::TempDir t("values_ranged");
  const std::array<int, 3> n{9, 8, 7};
  std::vector<uint16_t> data((size_t)n[0] * n[1] * n[2]);
  for (size_t i = 0; i < data.size(); ++i) data[i] = (uint16_t)(300 + (i * 2654435761u) % 700);
  RawVolumeReader reader(test::rawSpec(t.write("r.raw", data.data(), data.size() * 2), n, VoxelType::UInt16,
                                       {1, 1, 1}, true, {0, 4095}));
  const Volume v = reader.readValues(VoxelBox{{0, 0, 0}, n});
  EXPECT_EQ(v.data_range, (std::array<double, 2>{(double)*std::min_element(data.begin(), data.end()),
                                                 (double)*std::max_element(data.begin(), data.end())}));
  EXPECT_EQ(v.values[5], data[5]) << "not normalised";
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

// A cropped scene's bricks are balanced by the visible blocks inside the crop: blocks
// wholly outside count for nothing, and with the left half cropped, each of 4 bricks takes
// a share of that half rather than 2 of the 4 rendering nothing.
TEST(VolumeSummary, BricksAreBalancedByTheBlocksInsideTheCrop) {
  Scene scene = defaultScene();
  scene.volume = GeneratorSpec{"hollow-shell", 64, 1, {1, 1, 1}};
  const VolumeSummary s = summarizeVolume(scene);
  Crop crop;
  crop.axes[0] = {0, 0.5};
  const std::vector<uint8_t> all = visibleBlocks(s, scene.tf), inside = visibleBlocks(s, scene.tf, crop);
  int kept = 0;
  for (int z = 0; z < s.blocks[2]; ++z)
    for (int y = 0; y < s.blocks[1]; ++y)
      for (int x = 0; x < s.blocks[0]; ++x) {
        const size_t i = x + (size_t)s.blocks[0] * (y + (size_t)s.blocks[1] * z);
        EXPECT_EQ(inside[i], x * s.edge < 32 ? all[i] : 0) << x << " " << y << " " << z;
        kept += inside[i];
      }
  EXPECT_GT(kept, 0);
  const BrickTree tree = splitBricks(s, 4, scene.tf, crop);
  for (const BrickBox& b : tree.bricks) EXPECT_LT(b.lo[0], 32) << "a brick wholly outside the crop";
}

// A few slices of a big image: blocks of 8 on the long axes (one block across the thin one),
// not of one voxel, and bricks still split it (across the long axes).
TEST(VolumeSummary, AThinVolumeKeepsBlocksOfEight) {
  test::TempDir t("summary_thin");
  const std::array<int, 3> n{300, 280, 3};
  std::vector<uint8_t> data((size_t)n[0] * n[1] * n[2]);
  for (size_t i = 0; i < data.size(); ++i) data[i] = (uint8_t)((i * 2654435761u) >> 24);
  Scene scene = defaultScene();
  scene.volume = test::rawSpec(t.write("thin.raw", data.data(), data.size()), n, VoxelType::UInt8, {1, 1, 1}, false, {0, 0});
  const VolumeSummary s = summarizeVolume(scene);
  EXPECT_EQ(s.edge, 8);
  EXPECT_EQ(s.blocks, (std::array<int, 3>{38, 35, 1}));
  expectBlocksOfWhole(s, loadVolume(scene));
  for (int count : {2, 4, 8}) {
    const BrickTree tree = splitBricks(s, count, scene.tf);
    ASSERT_EQ((int)tree.bricks.size(), count);
    long long voxels = 0;
    for (const BrickBox& b : tree.bricks) voxels += (long long)(b.hi[0] - b.lo[0]) * (b.hi[1] - b.lo[1]) * (b.hi[2] - b.lo[2]);
    EXPECT_EQ(voxels, 300LL * 280 * 3) << count;
  }
}

}  // namespace
}  // namespace tessera
