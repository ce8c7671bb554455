// The caster's per-volume data from one pass: the bricked copy holds every voxel (with the
// apron) quantized, the hierarchy is exactly the one built from the volume on its own, and
// non-finite values are found.
#include "renderer/volume/volume_accel.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace tessera::renderer {
namespace {

Volume randomVolume(std::array<int, 3> dims, uint32_t seed) {
  Volume v;
  v.dims = dims;
  v.values.resize(v.voxelCount());
  for (float& x : v.values) {
    seed = seed * 1664525u + 1013904223u;
    x = (float)((seed >> 8) / 16777216.0 * 1.2 - 0.1);  // some outside [0, 1]: clamped when quantized
  }
  return v;
}

TEST(VolumeAccel, OnePassGivesTheVolumesOwnHierarchyAndEveryVoxelBricked) {
  // Largest first: each later volume is built in the bricked memory its predecessor left.
  for (const auto& dims : {std::array<int, 3>{70, 33, 41}, {20, 17, 9}, {17, 9, 9}, {9, 9, 9}, {1, 1, 1}}) {
    SCOPED_TRACE(std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]));
    const Volume v = randomVolume(dims, 7u + (uint32_t)dims[0]);
    const VolumeAccel a(v);
    const MinMaxHierarchy h(v);
    EXPECT_TRUE(a.all_finite);
    ASSERT_EQ(a.hierarchy.levels(), h.levels());
    for (int l = 0; l < h.levels(); ++l) {
      const auto d = h.dims(l);
      ASSERT_EQ(a.hierarchy.dims(l), d);
      for (int z = 0; z < d[2]; ++z)
        for (int y = 0; y < d[1]; ++y)
          for (int x = 0; x < d[0]; ++x) {
            ASSERT_EQ(a.hierarchy.minValue(l, x, y, z), h.minValue(l, x, y, z)) << l << " " << x << " " << y << " " << z;
            ASSERT_EQ(a.hierarchy.maxValue(l, x, y, z), h.maxValue(l, x, y, z)) << l << " " << x << " " << y << " " << z;
          }
    }
    // Every slot of every brick: its voxels and apron, the last voxel repeated past the far borders.
    constexpr int B = MinMaxHierarchy::kBlock, E = VolumeAccel::kEdge;
    size_t at = 0;
    for (int bz = 0; bz < a.nb[2]; ++bz)
      for (int by = 0; by < a.nb[1]; ++by)
        for (int bx = 0; bx < a.nb[0]; ++bx)
          for (int lz = 0; lz < E; ++lz)
            for (int ly = 0; ly < E; ++ly)
              for (int lx = 0; lx < E; ++lx, ++at) {
                const float x = v.at(std::min(B * bx + lx, dims[0] - 1), std::min(B * by + ly, dims[1] - 1),
                                     std::min(B * bz + lz, dims[2] - 1));
                const auto want = (uint16_t)(std::clamp(x, 0.0f, 1.0f) * VolumeAccel::kQuantScale + 0.5f);
                ASSERT_EQ(a.bricked[at], want) << "brick " << bx << " " << by << " " << bz << " slot " << lx << " " << ly << " " << lz;
              }
  }
}

TEST(VolumeAccel, FindsNonFiniteValues) {
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    -std::numeric_limits<float>::infinity()}) {
    // The last voxel (only the far bricks' aprons reach it), one in each half of a brick's
    // row, and one that is the ninth voxel of one brick and the first of the next.
    for (const auto& [x, y, z] : {std::array<int, 3>{19, 16, 8}, {2, 5, 1}, {6, 3, 4}, {8, 9, 0}}) {
      Volume v = randomVolume({20, 17, 9}, 3);
      v.values[v.index(x, y, z)] = bad;
      EXPECT_FALSE(VolumeAccel(v).all_finite) << bad << " at " << x << " " << y << " " << z;
    }
    // x = 16 of 17 voxels is only the apron of the last brick (its scalar ninth voxel).
    Volume v = randomVolume({17, 9, 9}, 4);
    v.values[v.index(16, 3, 3)] = bad;
    EXPECT_FALSE(VolumeAccel(v).all_finite) << bad << " in an apron";
  }
}

}  // namespace
}  // namespace tessera::renderer
