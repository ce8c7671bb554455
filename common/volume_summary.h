// What the master knows of a volume without holding it: its shape, the data's value range
// and the value range of every block of edge^3 voxels, found by streaming the volume
// through once in slabs of `edge` slices (memory: one slab). Enough to split the volume
// into bricks balanced by what may be visible, to order them, and to warn about a range
// that misses the data.
#pragma once
#include <array>
#include <atomic>
#include <cstdint>
#include <vector>

#include "common/bricks.h"
#include "common/scene.h"
#include "common/transfer_function.h"
#include "common/volume.h"

namespace tessera {

struct VolumeSummary {
  Volume shape;                        // dims, spacing, data_range, mapped_range; no values
  int edge = 8;                        // voxels per block edge
  std::array<int, 3> blocks{0, 0, 0};  // ceil(dims / edge)
  std::vector<float> lo, hi;           // normalised value range of each block's voxels, x fastest
};

// Blocks of 8 voxels, or fewer for a small volume so that there are at least 8^3 blocks
// (bricks are cut on block faces). Throws as loadVolume does.
// `cancel`, when raised, ends the reading at the next slab with std::runtime_error.
VolumeSummary summarizeVolume(const Scene& scene, const std::atomic<bool>* cancel = nullptr);
// 1 for every block that may be visible under tf (some value of its range has opacity) and
// reaches into the crop box.
std::vector<uint8_t> visibleBlocks(const VolumeSummary& s, const TransferFunction& tf, const Crop& crop = {});
// n bricks cut on block faces, balanced by the blocks that may be visible.
BrickTree splitBricks(const VolumeSummary& s, int n, const TransferFunction& tf, const Crop& crop = {});

// Fixes a raw volume's normalisation to the whole file's: with no `range`, the data's
// min..max, found by streaming the file once; later windows then load without a scan.
// Returns the data's value range.
std::array<double, 2> fixVolumeRange(Scene& scene);

}  // namespace tessera
