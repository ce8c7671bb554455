// Sub-block occupancy of the bricked volume for one transfer function (see occupancy.h).
#include "renderer/volume/occupancy.h"

#include <algorithm>

#include "common/parallel.h"
#include "renderer/volume/tf_table.h"

namespace tessera::renderer {

namespace {

constexpr int E = VolumeAccel::kEdge, S = MinMaxHierarchy::kBlock / 2;  // 9 voxels, 4 sub-blocks an edge
static_assert(MinMaxHierarchy::kBlock == 8, "a brick is 4^3 sub-blocks of 2^3 cells");

// Range of each sub-block's 3^3 voxels (2s..2s+2 on each axis): reduced along x, then y, then z.
void subBlockRanges(const uint16_t* brick, uint16_t mn[S * S * S], uint16_t mx[S * S * S]) {
  uint16_t xl[E][E][S], xh[E][E][S];  // [z][y][sx]
  for (int z = 0; z < E; ++z)
    for (int y = 0; y < E; ++y) {
      const uint16_t* r = brick + E * (y + E * z);
      for (int s = 0; s < S; ++s) {
        xl[z][y][s] = std::min({r[2 * s], r[2 * s + 1], r[2 * s + 2]});
        xh[z][y][s] = std::max({r[2 * s], r[2 * s + 1], r[2 * s + 2]});
      }
    }
  uint16_t yl[E][S][S], yh[E][S][S];  // [z][sy][sx]
  for (int z = 0; z < E; ++z)
    for (int sy = 0; sy < S; ++sy)
      for (int sx = 0; sx < S; ++sx) {
        yl[z][sy][sx] = std::min({xl[z][2 * sy][sx], xl[z][2 * sy + 1][sx], xl[z][2 * sy + 2][sx]});
        yh[z][sy][sx] = std::max({xh[z][2 * sy][sx], xh[z][2 * sy + 1][sx], xh[z][2 * sy + 2][sx]});
      }
  for (int sz = 0; sz < S; ++sz)
    for (int sy = 0; sy < S; ++sy)
      for (int sx = 0; sx < S; ++sx) {
        const int b = sx + S * (sy + S * sz);
        mn[b] = std::min({yl[2 * sz][sy][sx], yl[2 * sz + 1][sy][sx], yl[2 * sz + 2][sy][sx]});
        mx[b] = std::max({yh[2 * sz][sy][sx], yh[2 * sz + 1][sy][sx], yh[2 * sz + 2][sy][sx]});
      }
}

}  // namespace

std::vector<uint64_t> subBlockOccupancy(const VolumeAccel& accel, const MinMaxHierarchy::Emptiness& emptiness,
                                        const TransferFunction& tf) {
  const auto& nb = accel.nb;
  const long long bricks = (long long)nb[0] * nb[1] * nb[2];
  std::vector<uint64_t> bits((size_t)bricks, 0);
  // Per table entry t, whether [t, t+1] (scaled to [0, 1]) can hold opacity, as prefix counts:
  // a range is empty if every entry span it meets is (a span's test widens it as the table
  // reads). One test per entry instead of one per sub-block (~340 k in a 256^3 frame: 7 ms).
  constexpr int N = TfTable::kEntries;
  std::vector<int> lit(N + 1, 0);
  for (int t = 0; t < N; ++t)
    lit[t + 1] = lit[t] + (TfTable::rangeIsEmpty(tf, (float)t / (N - 1), (float)(t + 1) / (N - 1)) ? 0 : 1);
  auto entry = [](uint16_t q) { return std::min(N - 1, (int)((double)q * (N - 1) / VolumeAccel::kQuantScale)); };
  auto fill = [&](long long begin, long long end) {
    uint16_t mn[S * S * S], mx[S * S * S];
    for (long long b = begin; b < end; ++b) {
      if (emptiness.empty[0][(size_t)b]) continue;
      subBlockRanges(&accel.bricked[(size_t)b * VolumeAccel::kBrickSize], mn, mx);
      uint64_t m = 0;
      for (int s = 0; s < S * S * S; ++s)
        if (lit[entry(mx[s]) + 1] > lit[entry(mn[s])]) m |= uint64_t{1} << s;
      bits[(size_t)b] = m;
    }
  };
  parallelRanges(bricks, bricks > 4096 ? 2 : 1, fill);
  return bits;
}

}  // namespace tessera::renderer
