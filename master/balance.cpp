#include "master/balance.h"

#include <algorithm>
#include <numeric>

namespace tessera::master {

std::vector<Rect> balancedBands(int width, int height, int m, const std::vector<Rect>& active) {
  m = std::clamp(m, 1, height);
  // Active pixels per row; each renderer's rectangle counts (overlaps cost compositing work).
  std::vector<double> rows(height, 0.0);
  for (const Rect& a : active) {
    Rect r = intersect(a, Rect{0, 0, width, height});
    for (int y = r.y; y < r.y + r.h && !r.empty(); ++y) rows[y] += r.w;
  }
  // A floor per row keeps empty rows from collapsing every band onto the busy ones.
  double total = std::accumulate(rows.begin(), rows.end(), 0.0);
  for (double& v : rows) v += total > 0 ? total * 1e-4 / height : 1.0;
  total = std::accumulate(rows.begin(), rows.end(), 0.0);

  std::vector<Rect> bands;
  int y0 = 0;
  double acc = 0;
  for (int y = 0; y < height && (int)bands.size() < m - 1; ++y) {
    acc += rows[y];
    int remaining_bands = m - 1 - (int)bands.size();
    bool must_cut = height - (y + 1) == remaining_bands;  // leave one row per band left
    if (acc >= total * (bands.size() + 1) / m || must_cut) {
      bands.push_back({0, y0, width, y + 1 - y0});
      y0 = y + 1;
    }
  }
  bands.push_back({0, y0, width, height - y0});
  return bands;
}

double imbalance(const std::vector<double>& work) {
  if (work.empty()) return 1;
  double mx = *std::max_element(work.begin(), work.end());
  double mean = std::accumulate(work.begin(), work.end(), 0.0) / work.size();
  return mean > 0 ? mx / mean : 1;
}

}  // namespace tessera::master
