// Empty-space skipping inside a non-empty block: which 2^3-cell sub-blocks of each 8^3-cell
// brick can hold a sample of non-zero opacity under one transfer function. The min-max
// hierarchy's leaper passes over empty 8^3 blocks; on thin or sparse matter most samples it
// takes are still transparent (59% in the hollow shell's default frame, inside non-empty
// blocks). The fast kernel tests a packet's sub-blocks with one gather before it fetches
// any voxel, and passes over a packet whose every sample lies in an empty sub-block.
#pragma once
#include <cstdint>
#include <vector>

#include "common/transfer_function.h"
#include "renderer/volume/minmax.h"
#include "renderer/volume/volume_accel.h"

namespace tessera::renderer {

// One 64-bit mask per brick of `accel` (its bricked order): bit sx + 4*sy + 16*sz is set
// unless every sample whose lower corner has local cell (2sx..2sx+1, 2sy.., 2sz..) in the brick
// classifies to exactly zero opacity. A sample interpolates 8 voxels of its sub-block's 3^3,
// so its value lies within their range; TfTable::rangeIsEmpty widens that range by the
// table's reach. Blocks `emptiness` marks empty get 0 without a look at their voxels.
std::vector<uint64_t> subBlockOccupancy(const VolumeAccel& accel, const MinMaxHierarchy::Emptiness& emptiness,
                                        const TransferFunction& tf);

// The bit of a sample whose lower corner is voxel i (i >= 0 on each axis) in its brick's mask.
inline int subBlockBit(int ix, int iy, int iz) { return ((ix >> 1) & 3) | ((iy >> 1) & 3) << 2 | ((iz >> 1) & 3) << 4; }

}  // namespace tessera::renderer
