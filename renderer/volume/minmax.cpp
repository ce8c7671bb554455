// Min-max hierarchy construction and per-transfer-function classification.
#include "renderer/volume/minmax.h"

#include <algorithm>
#include <stdexcept>
#include <thread>

#include "common/parallel.h"

namespace tessera::renderer {

namespace {
int blocksOnAxis(int n) { return std::max(1, (n - 2) / MinMaxHierarchy::kBlock + 1); }

// Forward-octant chessboard distance: one pass from the far corner of the octant, since
// the cube at b is empty iff b is and the seven cubes (one smaller) at its forward
// neighbours are.
void octantDistance(const std::array<int, 3>& d, const std::vector<uint8_t>& empty, int octant, std::vector<uint8_t>& out) {
  const int nx = d[0], ny = d[1], nz = d[2];
  const int sx = (octant & 1) ? -1 : 1, sy = (octant & 2) ? -1 : 1, sz = (octant & 4) ? -1 : 1;
  out.assign(empty.size(), 0);
  auto idx = [&](int x, int y, int z) { return x + (size_t)nx * (y + (size_t)ny * z); };
  for (int iz = 0; iz < nz; ++iz)
    for (int iy = 0; iy < ny; ++iy)
      for (int ix = 0; ix < nx; ++ix) {
        // Visit forward neighbours first: start at the far end of every axis.
        const int x = sx > 0 ? nx - 1 - ix : ix, y = sy > 0 ? ny - 1 - iy : iy, z = sz > 0 ? nz - 1 - iz : iz;
        if (!empty[idx(x, y, z)]) continue;
        int m = 254;  // beyond the grid counts as empty (positions clamp into border blocks)
        for (int e = 1; e < 8; ++e) {
          const int X = x + ((e & 1) ? sx : 0), Y = y + ((e & 2) ? sy : 0), Z = z + ((e & 4) ? sz : 0);
          if (X < 0 || Y < 0 || Z < 0 || X >= nx || Y >= ny || Z >= nz) continue;
          m = std::min<int>(m, out[idx(X, Y, Z)]);
        }
        out[idx(x, y, z)] = (uint8_t)(m + 1);
      }
}
}  // namespace

std::array<int, 3> MinMaxHierarchy::blockDims(const std::array<int, 3>& n) {
  return {blocksOnAxis(n[0]), blocksOnAxis(n[1]), blocksOnAxis(n[2])};
}

MinMaxHierarchy::MinMaxHierarchy(const std::array<int, 3>& block_dims, std::vector<float> mn, std::vector<float> mx) {
  if (mn.size() != (size_t)block_dims[0] * block_dims[1] * block_dims[2] || mx.size() != mn.size())
    throw std::invalid_argument("MinMaxHierarchy: level 0 size differs from its block dims");
  levels_.push_back(Level{block_dims, std::move(mn), std::move(mx)});
  buildCoarserLevels();
}

MinMaxHierarchy::MinMaxHierarchy(const Volume& v) {
  const auto& n = v.dims;
  if (v.values.size() != v.voxelCount() || v.voxelCount() == 0)
    throw std::invalid_argument("MinMaxHierarchy: volume has no voxels or wrong value count");
  Level l0;
  l0.dims = blockDims(n);
  const size_t count = (size_t)l0.dims[0] * l0.dims[1] * l0.dims[2];
  l0.mn.assign(count, 0);
  l0.mx.assign(count, 0);
  // Slabs of blocks along z, one per thread.
  auto work = [&](int bz0, int bz1) {
    for (int bz = bz0; bz < bz1; ++bz)
      for (int by = 0; by < l0.dims[1]; ++by)
        for (int bx = 0; bx < l0.dims[0]; ++bx) {
          const int b[3] = {bx, by, bz};
          int lo[3], hi[3];  // inclusive voxel range incl. the +1 apron
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(b[a] * kBlock, n[a] - 1);
            hi[a] = std::min(b[a] * kBlock + kBlock, n[a] - 1);
          }
          float mn = v.at(lo[0], lo[1], lo[2]), mx = mn;
          for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y) {
              const float* row = &v.values[v.index(0, y, z)];
              for (int x = lo[0]; x <= hi[0]; ++x) {
                mn = std::min(mn, row[x]);
                mx = std::max(mx, row[x]);
              }
            }
          size_t i = bx + (size_t)l0.dims[0] * (by + (size_t)l0.dims[1] * bz);
          l0.mn[i] = mn;
          l0.mx[i] = mx;
        }
  };
  const int nz = l0.dims[2];
  const bool big = nz >= 4 && v.voxelCount() >= (1u << 18);  // threads cost more than small volumes
  parallelRanges(nz, big ? 2 : 1, [&](long long z0, long long z1) { work((int)z0, (int)z1); });
  levels_.push_back(std::move(l0));
  buildCoarserLevels();
}

// Octree levels: each node covers 2x2x2 nodes of the finer level.
void MinMaxHierarchy::buildCoarserLevels() {
  while (levels_.back().dims != std::array<int, 3>{1, 1, 1}) {
    const Level& f = levels_.back();
    Level c;
    for (int a = 0; a < 3; ++a) c.dims[a] = (f.dims[a] + 1) / 2;
    const size_t cc = (size_t)c.dims[0] * c.dims[1] * c.dims[2];
    c.mn.assign(cc, 1e30f);
    c.mx.assign(cc, -1e30f);
    for (int z = 0; z < f.dims[2]; ++z)
      for (int y = 0; y < f.dims[1]; ++y)
        for (int x = 0; x < f.dims[0]; ++x) {
          size_t fi = x + (size_t)f.dims[0] * (y + (size_t)f.dims[1] * z);
          size_t ci = x / 2 + (size_t)c.dims[0] * (y / 2 + (size_t)c.dims[1] * (z / 2));
          c.mn[ci] = std::min(c.mn[ci], f.mn[fi]);
          c.mx[ci] = std::max(c.mx[ci], f.mx[fi]);
        }
    levels_.push_back(std::move(c));
  }
}

MinMaxHierarchy::Emptiness MinMaxHierarchy::classify(const std::function<bool(float, float)>& isEmpty) const {
  Emptiness e;
  e.empty.resize(levels_.size());
  const Level& l0 = levels_[0];
  e.empty[0].resize(l0.mn.size());
  std::array<int, 3> lo = l0.dims, hi{0, 0, 0};
  for (int z = 0; z < l0.dims[2]; ++z)
    for (int y = 0; y < l0.dims[1]; ++y)
      for (int x = 0; x < l0.dims[0]; ++x) {
        const size_t i = index(0, x, y, z);
        e.empty[0][i] = isEmpty(l0.mn[i], l0.mx[i]) ? 1 : 0;
        e.empty_blocks += e.empty[0][i];
        if (e.empty[0][i]) continue;
        const int b[3] = {x, y, z};
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], b[a]), hi[a] = std::max(hi[a], b[a] + 1);
      }
  if (hi[0] > 0) e.nonempty_lo = lo, e.nonempty_hi = hi;
  for (int o = 0; o < 8; ++o) octantDistance(l0.dims, e.empty[0], o, e.octant_distance[o]);
  for (size_t l = 1; l < levels_.size(); ++l) {
    const Level& f = levels_[l - 1];
    const Level& c = levels_[l];
    e.empty[l].assign(c.mn.size(), 1);
    for (int z = 0; z < f.dims[2]; ++z)
      for (int y = 0; y < f.dims[1]; ++y)
        for (int x = 0; x < f.dims[0]; ++x) {
          size_t fi = x + (size_t)f.dims[0] * (y + (size_t)f.dims[1] * z);
          size_t ci = x / 2 + (size_t)c.dims[0] * (y / 2 + (size_t)c.dims[1] * (z / 2));
          e.empty[l][ci] &= e.empty[l - 1][fi];
        }
  }
  return e;
}

}  // namespace tessera::renderer
