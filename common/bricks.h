// Splitting a volume into bricks (k-d tree) and ordering them front to back.
// Splits balance non-empty voxels (opacity > 0 under the transfer function), not volume.
#pragma once
#include <vector>

#include "common/camera.h"
#include "common/transfer_function.h"
#include "common/volume.h"

namespace tessera {

using BrickBox = VoxelBox;  // voxel index box [lo, hi)

struct BrickTree {
  std::vector<BrickBox> bricks;  // leaves, in split order
  struct Node { int axis = -1; int split = 0; int left = -1, right = -1; int leaf = -1; };
  std::vector<Node> nodes;      // nodes[0] is the root
  // Leaf indices front to back as seen from the camera (BSP order: exact for convex boxes).
  std::vector<int> visibilityOrder(const Volume& v, const Camera& cam) const;
};

// n bricks (n >= 1, capped so every brick has at least one voxel per axis).
// With a transfer function, splits balance voxels whose alpha > 0; otherwise voxel counts.
BrickTree splitBricks(const Volume& v, int n, const TransferFunction* tf = nullptr);
// The same split over any grid of `dims` cells: mask[cell] = 1 where it may be visible
// (null: every cell counts).
BrickTree splitMask(const std::array<int, 3>& dims, const std::vector<uint8_t>* mask, int n);
// A split of a grid of edge^3-voxel blocks made a split of the voxels: every box and split
// scaled by `edge` and clamped to the volume's `dims`. Each brick keeps at least one voxel
// per axis as long as the grid has ceil(dims / edge) cells.
BrickTree scaleBricks(BrickTree tree, int edge, const std::array<int, 3>& dims);

}  // namespace tessera
