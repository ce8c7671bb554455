// Min-max hierarchy for empty-space skipping: value ranges of 8^3-cell blocks (with the
// one-voxel apron that trilinear sampling touches) and an octree of coarser levels.
// Built once per volume (immutable, shareable); emptiness is classified per transfer function.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "common/volume.h"

namespace tessera::renderer {

// A sample at voxel coordinate u (voxel centres at integers) is clamped to [0, n-1] and
// reads voxels i and i+1 with i = clamp(floor(u), 0, n-2). Block b on an axis holds the
// samples with i in [8b, 8b+8), so it reads voxels [8b, min(8b+8, n-1)].
class MinMaxHierarchy {
 public:
  static constexpr int kBlock = 8;  // cells per block edge at level 0

  explicit MinMaxHierarchy(const Volume& v);
  // From level 0 computed elsewhere (VolumeAccel gets it in the pass that bricks the values):
  // `mn`, `mx` hold blockDims(voxel dims) blocks, x fastest.
  MinMaxHierarchy(const std::array<int, 3>& block_dims, std::vector<float> mn, std::vector<float> mx);
  // Level-0 blocks per axis for a volume of `voxel_dims`.
  static std::array<int, 3> blockDims(const std::array<int, 3>& voxel_dims);

  int levels() const { return (int)levels_.size(); }
  std::array<int, 3> dims(int level) const { return levels_[level].dims; }
  // Range of voxel values a sample inside node (x,y,z) of `level` can interpolate from.
  float minValue(int level, int x, int y, int z) const { return levels_[level].mn[index(level, x, y, z)]; }
  float maxValue(int level, int x, int y, int z) const { return levels_[level].mx[index(level, x, y, z)]; }
  size_t index(int level, int x, int y, int z) const {
    const auto& d = levels_[level].dims;
    return x + (size_t)d[0] * (y + (size_t)d[1] * z);
  }

  // Per-level empty flags: level 0 block empty iff isEmpty(min, max); a coarser node is
  // empty iff all its children are.
  struct Emptiness {
    std::vector<std::vector<uint8_t>> empty;  // [level][node index]
    uint64_t empty_blocks = 0;                // level-0 blocks marked empty
    // Directional chessboard distance maps, one per octant of ray directions (bit a set:
    // negative along axis a). octant_distance[o][b] = d means the d^3 cube of blocks that
    // starts at b and extends d-1 blocks forward along every axis of octant o is empty
    // (0: b itself is non-empty; capped at 255). A ray only moves forward, so it can leap
    // across that cube in one step; moving away from matter the cubes grow quickly.
    std::array<std::vector<uint8_t>, 8> octant_distance;
    // Bounding box of the non-empty level-0 blocks, [lo, hi) in block indices; lo == hi
    // on every axis when every block is empty.
    std::array<int, 3> nonempty_lo{0, 0, 0}, nonempty_hi{0, 0, 0};
    bool allEmpty() const { return nonempty_lo[0] >= nonempty_hi[0]; }
  };
  Emptiness classify(const std::function<bool(float lo, float hi)>& isEmpty) const;

 private:
  struct Level {
    std::array<int, 3> dims{1, 1, 1};
    std::vector<float> mn, mx;
  };
  void buildCoarserLevels();
  std::vector<Level> levels_;
};

}  // namespace tessera::renderer
