#include "master/tiling.h"

#include <algorithm>
#include <cmath>

namespace tessera::master {

CostGrid::CostGrid(int width, int height, int cells)
    : width_(width), height_(height), cx_(std::min(cells, width)), cy_(std::min(cells, height)),
      ms_((size_t)cx_ * cy_, 0.0) {}

CostGrid CostGrid::resized(int width, int height) const {
  if (width < cx_ || height < cy_) return CostGrid(width, height);
  CostGrid g = *this;
  g.width_ = width;
  g.height_ = height;
  return g;
}

Rect CostGrid::cell(int i, int j) const {
  int x0 = (int)((long long)i * width_ / cx_), x1 = (int)((long long)(i + 1) * width_ / cx_);
  int y0 = (int)((long long)j * height_ / cy_), y1 = (int)((long long)(j + 1) * height_ / cy_);
  return {x0, y0, x1 - x0, y1 - y0};
}

void CostGrid::add(const Rect& tile, double ms) {
  if (tile.empty() || !(ms > 0)) return;
  for (int j = 0; j < cy_; ++j)
    for (int i = 0; i < cx_; ++i) {
      double share = (double)intersect(tile, cell(i, j)).area() / (double)tile.area();
      ms_[(size_t)j * cx_ + i] += ms * share;
    }
  total_ += ms;
}

double CostGrid::cost(const Rect& r) const {
  double c = 0;
  for (int j = 0; j < cy_; ++j)
    for (int i = 0; i < cx_; ++i) {
      Rect cl = cell(i, j);
      long long covered = intersect(r, cl).area();
      if (covered) c += ms_[(size_t)j * cx_ + i] * (double)covered / (double)cl.area();
    }
  return c;
}

std::vector<Rect> equalTiles(int width, int height, int n) {
  n = (int)std::max<long long>(1, std::min<long long>(n, (long long)width * height));
  int cols = std::max(1, (int)std::lround(std::sqrt((double)n * width / height)));
  cols = std::min({cols, n, width});
  std::vector<Rect> tiles;
  int rows = (n + cols - 1) / cols;
  for (int r = 0, k = 0; r < rows; ++r) {
    int in_row = std::min(cols, n - k);
    int y0 = (int)((long long)r * height / rows), y1 = (int)((long long)(r + 1) * height / rows);
    for (int c = 0; c < in_row; ++c, ++k) {
      int x0 = (int)((long long)c * width / in_row), x1 = (int)((long long)(c + 1) * width / in_row);
      tiles.push_back({x0, y0, x1 - x0, y1 - y0});
    }
  }
  return tiles;
}

namespace {

// Cost with a floor per pixel, so empty screen still counts a little and cuts stay sane.
double weighted(const CostGrid& g, const Rect& r, double floor_per_px) { return g.cost(r) + floor_per_px * r.area(); }

void split(const Rect& r, int n, const CostGrid& g, double floor_per_px, std::vector<Rect>& out) {
  if (n <= 1 || r.area() < 2) {
    out.push_back(r);
    return;
  }
  bool vertical = r.w >= r.h;  // cut across the longer side
  int len = vertical ? r.w : r.h;
  if (len < 2) vertical = !vertical, len = vertical ? r.w : r.h;
  int n1 = n / 2, n2 = n - n1;
  double want = weighted(g, r, floor_per_px) * n1 / n;
  // The first cut position whose left/top part reaches the wanted share (monotone in pos).
  int lo = 1, hi = len - 1;
  auto part = [&](int pos) { return vertical ? Rect{r.x, r.y, pos, r.h} : Rect{r.x, r.y, r.w, pos}; };
  while (lo < hi) {
    int mid = (lo + hi) / 2;
    if (weighted(g, part(mid), floor_per_px) < want) lo = mid + 1;
    else hi = mid;
  }
  Rect a = part(lo);
  Rect b = vertical ? Rect{r.x + lo, r.y, r.w - lo, r.h} : Rect{r.x, r.y + lo, r.w, r.h - lo};
  split(a, n1, g, floor_per_px, out);
  split(b, n2, g, floor_per_px, out);
}

}  // namespace

std::vector<Rect> balancedTiles(int width, int height, int n, const CostGrid& cost) {
  if (cost.empty()) return equalTiles(width, height, n);
  n = (int)std::max<long long>(1, std::min<long long>(n, (long long)width * height));
  std::vector<Rect> out;
  Rect screen{0, 0, width, height};
  split(screen, n, cost, 1e-3 * cost.cost(screen) / screen.area(), out);
  return out;
}

}  // namespace tessera::master
