// The caster's per-volume data from one pass: the bricked copy holds every voxel (with the
// apron) quantized, the hierarchy is exactly the one built from the volume on its own, and
// non-finite values are found.
#include "renderer/volume/volume_accel.h"

#include <gtest/gtest.h>

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
  for (const auto& dims : {std::array<int, 3>{1, 1, 1}, {9, 9, 9}, {20, 17, 9}, {70, 33, 41}}) {
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
    constexpr int B = MinMaxHierarchy::kBlock, E = VolumeAccel::kEdge;
    for (int z = 0; z < dims[2]; ++z)
      for (int y = 0; y < dims[1]; ++y)
        for (int x = 0; x < dims[0]; ++x) {
          // The voxel as the last brick holding it on every axis stores it (brick b holds 8b..8b+8).
          const int b[3] = {std::min(x / B, a.nb[0] - 1), std::min(y / B, a.nb[1] - 1), std::min(z / B, a.nb[2] - 1)};
          const size_t at = VolumeAccel::kBrickSize * (b[0] + (size_t)a.nb[0] * (b[1] + (size_t)a.nb[1] * b[2])) +
                            (x - B * b[0]) + E * ((y - B * b[1]) + E * (z - B * b[2]));
          const auto want = (uint16_t)(std::clamp(v.at(x, y, z), 0.0f, 1.0f) * VolumeAccel::kQuantScale + 0.5f);
          ASSERT_EQ(a.bricked[at], want) << x << " " << y << " " << z;
        }
  }
}

TEST(VolumeAccel, FindsNonFiniteValues) {
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                    -std::numeric_limits<float>::infinity()}) {
    // The last voxel (only the far bricks' aprons reach it), one in each half of a brick's
    // row and its ninth (apron) voxel.
    for (const auto& [x, y, z] : {std::array<int, 3>{19, 16, 8}, {2, 5, 1}, {6, 3, 4}, {8, 9, 0}}) {
      Volume v = randomVolume({20, 17, 9}, 3);
      v.values[v.index(x, y, z)] = bad;
      EXPECT_FALSE(VolumeAccel(v).all_finite) << bad << " at " << x << " " << y << " " << z;
    }
  }
}

}  // namespace
}  // namespace tessera::renderer
