// Shared per-volume acceleration data (see volume_accel.h).
#include "renderer/volume/volume_accel.h"

#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <map>
#include <mutex>
#include <thread>
#include <algorithm>

#include "common/parallel.h"

namespace tessera::renderer {

struct VolumeAccel::Pass {
  std::array<int, 3> nb;
  decltype(VolumeAccel::bricked) bricked;
  std::vector<float> mn, mx;
  bool all_finite = true;
};

namespace {

// One brick: its 9^3 voxels (clamped at the far borders) quantized into `dst`, their range
// into mn/mx. Returns false if one is not finite.
bool fillBrick(const Volume& v, int bx, int by, int bz, uint16_t* dst, float& mn, float& mx) {
  constexpr int B = MinMaxHierarchy::kBlock, E = VolumeAccel::kEdge;
  float lo = v.values[v.index(std::min(bx * B, v.dims[0] - 1), std::min(by * B, v.dims[1] - 1), std::min(bz * B, v.dims[2] - 1))];
  float hi = lo;
  bool finite = true;
  for (int lz = 0; lz < E; ++lz) {
    const int z = std::min(bz * B + lz, v.dims[2] - 1);
    for (int ly = 0; ly < E; ++ly) {
      const int y = std::min(by * B + ly, v.dims[1] - 1);
      const float* row = &v.values[v.index(0, y, z)];
      for (int lx = 0; lx < E; ++lx) {
        const float x = row[std::min(bx * B + lx, v.dims[0] - 1)];
        finite &= std::abs(x) <= std::numeric_limits<float>::max();  // false for NaN and inf
        lo = std::min(lo, x);
        hi = std::max(hi, x);
        // std::clamp, not fmin/fmax: those are libm calls without -ffast-math (NaN rules),
        // 21% of a time step's preparation.
        *dst++ = (uint16_t)(std::clamp(x, 0.0f, 1.0f) * VolumeAccel::kQuantScale + 0.5f);
      }
    }
  }
  mn = lo, mx = hi;
  return finite;
}

}  // namespace

VolumeAccel::VolumeAccel(const Volume& v) : VolumeAccel([&v] {
  // Quantization error <= 0.5/65535 of the scalar: the table margin in TfTable::rangeIsEmpty
  // (2/4095) keeps empty-space decisions conservative for quantized samples.
  if (v.values.size() != v.voxelCount() || v.voxelCount() == 0)
    throw std::invalid_argument("VolumeAccel: volume has no voxels or wrong value count");
  Pass p;
  p.nb = MinMaxHierarchy::blockDims(v.dims);
  const size_t blocks = (size_t)p.nb[0] * p.nb[1] * p.nb[2];
  p.bricked.resize((size_t)kBrickSize * blocks + 8);  // uninitialised: the pass writes every brick
  std::fill(p.bricked.end() - 8, p.bricked.end(), uint16_t{0});
  p.mn.resize(blocks);
  p.mx.resize(blocks);
  std::atomic<bool> finite{true};
  auto fill = [&](long long bz0, long long bz1) {
    bool ok = true;
    for (int bz = (int)bz0; bz < (int)bz1; ++bz)
      for (int by = 0; by < p.nb[1]; ++by)
        for (int bx = 0; bx < p.nb[0]; ++bx) {
          const size_t b = bx + (size_t)p.nb[0] * (by + (size_t)p.nb[1] * bz);
          ok &= fillBrick(v, bx, by, bz, &p.bricked[kBrickSize * b], p.mn[b], p.mx[b]);
        }
    if (!ok) finite = false;
  };
  const bool big = p.nb[2] >= 4 && v.voxelCount() >= (1u << 18);  // threads cost more than small volumes
  parallelRanges(p.nb[2], big ? 2 : 1, fill);
  p.all_finite = finite;
  return p;
}()) {}

VolumeAccel::VolumeAccel(Pass&& p)
    : hierarchy(p.nb, std::move(p.mn), std::move(p.mx)), bricked(std::move(p.bricked)), nb(p.nb), all_finite(p.all_finite) {}

std::shared_ptr<const VolumeAccel> VolumeAccel::forVolume(const std::shared_ptr<const Volume>& v) {
  static std::mutex mu;
  static std::map<const Volume*, std::pair<std::weak_ptr<const Volume>, std::weak_ptr<const VolumeAccel>>> cache;
  std::lock_guard lock(mu);
  for (auto it = cache.begin(); it != cache.end();) {  // drop entries of freed volumes
    if (it->second.first.expired() || it->second.second.expired()) it = cache.erase(it);
    else ++it;
  }
  auto it = cache.find(v.get());
  if (it != cache.end() && it->second.first.lock() == v)
    if (auto a = it->second.second.lock()) return a;
  auto a = std::make_shared<const VolumeAccel>(*v);
  cache[v.get()] = {v, a};
  return a;
}

}  // namespace tessera::renderer
