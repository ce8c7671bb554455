// Empty-space skipping inside a non-empty block: which cells of each 8^3-cell brick can hold a
// sample of non-zero opacity under one transfer function. The min-max hierarchy's leaper
// passes over empty 8^3 blocks; on thin or sparse matter most samples it takes are still
// transparent (59% in the hollow shell's default frame, inside non-empty blocks). The fast
// kernel tests a packet's cells with one gather before it fetches any voxel, and passes over
// a packet whose every sample lies in an empty cell.
#pragma once
#include <cstdint>
#include <vector>

#include "common/transfer_function.h"
#include "renderer/volume/minmax.h"
#include "renderer/volume/volume_accel.h"

namespace tessera::renderer {

// kOccupancyWords 64-bit words per brick of `accel` (its bricked order): bit cellBit(i) of the
// brick's 512 is set unless every sample whose lower corner is cell i classifies to exactly
// zero opacity. A sample interpolates its cell's 2^3 voxels, so its value lies within their
// range; TfTable::rangeIsEmpty widens that range by the table's reach. Blocks `emptiness`
// marks empty get 0 without a look at their voxels.
inline constexpr int kOccupancyWords = 8;
std::vector<uint64_t> cellOccupancy(const VolumeAccel& accel, const MinMaxHierarchy::Emptiness& emptiness,
                                    const TransferFunction& tf);

// The bit, in its brick's 512, of the cell whose lower corner is voxel (ix, iy, iz) (>= 0).
inline int cellBit(int ix, int iy, int iz) { return (ix & 7) | (iy & 7) << 3 | (iz & 7) << 6; }

}  // namespace tessera::renderer
