// Cell occupancy of the bricked volume for one transfer function (see occupancy.h).
#include "renderer/volume/occupancy.h"

#include <algorithm>

#include "common/parallel.h"
#include "renderer/volume/tf_table.h"

namespace tessera::renderer {

namespace {

constexpr int kB = MinMaxHierarchy::kBlock, kE = VolumeAccel::kEdge;  // 8 cells, 9 voxels an edge
static_assert(kB * kB * kB == 64 * kOccupancyWords, "one bit per cell of a brick");

// Range of each cell's 2^3 voxels: reduced along x, then y, then z.
void cellRanges(const uint16_t* brick, uint16_t mn[kB * kB * kB], uint16_t mx[kB * kB * kB]) {
  uint16_t xl[kE][kE][kB], xh[kE][kE][kB];  // [z][y][cell x]
  for (int z = 0; z < kE; ++z)
    for (int y = 0; y < kE; ++y) {
      const uint16_t* r = brick + kE * (y + kE * z);
      for (int x = 0; x < kB; ++x) xl[z][y][x] = std::min(r[x], r[x + 1]), xh[z][y][x] = std::max(r[x], r[x + 1]);
    }
  uint16_t yl[kE][kB][kB], yh[kE][kB][kB];  // [z][cell y][cell x]
  for (int z = 0; z < kE; ++z)
    for (int y = 0; y < kB; ++y)
      for (int x = 0; x < kB; ++x)
        yl[z][y][x] = std::min(xl[z][y][x], xl[z][y + 1][x]), yh[z][y][x] = std::max(xh[z][y][x], xh[z][y + 1][x]);
  for (int z = 0; z < kB; ++z)
    for (int y = 0; y < kB; ++y)
      for (int x = 0; x < kB; ++x) {
        const int c = x + kB * (y + kB * z);
        mn[c] = std::min(yl[z][y][x], yl[z + 1][y][x]);
        mx[c] = std::max(yh[z][y][x], yh[z + 1][y][x]);
      }
}

}  // namespace

std::vector<uint64_t> cellOccupancy(const VolumeAccel& accel, const MinMaxHierarchy::Emptiness& emptiness,
                                    const TransferFunction& tf) {
  const auto& nb = accel.nb;
  const long long bricks = (long long)nb[0] * nb[1] * nb[2];
  std::vector<uint64_t> bits((size_t)bricks * kOccupancyWords, 0);
  // Per table entry t, whether [t, t+1] (scaled to [0, 1]) can hold opacity, as prefix counts:
  // a range is empty if every entry span it meets is (a span's test widens it as the table
  // reads). One test per entry instead of one per cell (~2.8 M in a 256^3 frame).
  constexpr int N = TfTable::kEntries;
  std::vector<int> lit(N + 1, 0);
  for (int t = 0; t < N; ++t)
    lit[t + 1] = lit[t] + (TfTable::rangeIsEmpty(tf, (float)t / (N - 1), (float)(t + 1) / (N - 1)) ? 0 : 1);
  // The entry a quantized value falls in, floor(q * 4095 / 65535) exactly (integers: a double
  // division per cell was most of this function's time).
  static_assert(VolumeAccel::kQuantScale == 65535.0f, "values are quantized to 16 bits");
  auto entry = [](uint16_t q) { return (int)((uint32_t)q * (N - 1) / 65535u); };
  auto fill = [&](long long begin, long long end) {
    uint16_t mn[kB * kB * kB], mx[kB * kB * kB];
    for (long long b = begin; b < end; ++b) {
      if (emptiness.empty[0][(size_t)b]) continue;
      cellRanges(&accel.bricked[(size_t)b * VolumeAccel::kBrickSize], mn, mx);
      uint64_t* words = &bits[(size_t)b * kOccupancyWords];
      for (int c = 0; c < kB * kB * kB; ++c)
        if (lit[entry(mx[c]) + 1] > lit[entry(mn[c])]) words[c / 64] |= uint64_t{1} << (c % 64);
    }
  };
  parallelRanges(bricks, bricks > 4096 ? 2 : 1, fill);
  return bits;
}

}  // namespace tessera::renderer
