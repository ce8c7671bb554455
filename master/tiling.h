// Sort-first screen partitioning: static equal tiles, or tiles re-cut every frame from the
// previous frame's measured per-tile render cost (a k-d split of the screen by cost), so
// that renderers finish together. Plain values; not thread-safe.
#pragma once
#include <vector>

#include "common/image.h"

namespace tessera::master {

// Render cost over the screen, kept on a coarse grid of cells (ms per cell).
class CostGrid {
 public:
  CostGrid(int width, int height, int cells = 32);
  // Spreads `ms` over `tile` in proportion to the pixels it covers in each cell.
  void add(const Rect& tile, double ms);
  // Cost of the pixels of `r` (cells partly covered count by area).
  double cost(const Rect& r) const;
  bool empty() const { return total_ <= 0; }
  // The same costs over an image of another size (each cell covers the same fraction of it);
  // an empty grid when the new size has fewer pixels than this grid has cells along an axis.
  CostGrid resized(int width, int height) const;

 private:
  int width_, height_, cx_, cy_;
  std::vector<double> ms_;  // per cell
  double total_ = 0;
  Rect cell(int i, int j) const;
};

// n tiles of (nearly) equal size in a near-square grid, row-major.
std::vector<Rect> equalTiles(int width, int height, int n);
// n tiles of (nearly) equal cost: recursively cut the longer side where the cost splits in
// the ratio of the renderers on each side. Equal tiles when the grid is empty.
std::vector<Rect> balancedTiles(int width, int height, int n, const CostGrid& cost);

}  // namespace tessera::master
