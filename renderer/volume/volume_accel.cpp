// Shared per-volume acceleration data (see volume_accel.h).
#include "renderer/volume/volume_accel.h"

#include <cmath>
#include <map>
#include <mutex>
#include <thread>
#include <algorithm>

#include "common/parallel.h"

namespace tessera::renderer {

VolumeAccel::VolumeAccel(const Volume& v) : hierarchy(v), nb(hierarchy.dims(0)) {
  // Quantization error <= 0.5/65535 of the scalar: the table margin in TfTable::rangeIsEmpty
  // (2/4095) keeps empty-space decisions conservative for quantized samples.
  constexpr int B = MinMaxHierarchy::kBlock;
  bricked.assign((size_t)kBrickSize * nb[0] * nb[1] * nb[2] + 8, 0);
  auto fill = [&](int bz0, int bz1) {
    for (int bz = bz0; bz < bz1; ++bz)
      for (int by = 0; by < nb[1]; ++by)
        for (int bx = 0; bx < nb[0]; ++bx) {
          uint16_t* dst = &bricked[(size_t)kBrickSize * (bx + (size_t)nb[0] * (by + (size_t)nb[1] * bz))];
          for (int lz = 0; lz < kEdge; ++lz) {
            const int z = std::min(bz * B + lz, v.dims[2] - 1);
            for (int ly = 0; ly < kEdge; ++ly) {
              const int y = std::min(by * B + ly, v.dims[1] - 1);
              const float* row = &v.values[v.index(0, y, z)];
              for (int lx = 0; lx < kEdge; ++lx) {
                const float x = row[std::min(bx * B + lx, v.dims[0] - 1)];
                // std::clamp, not fmin/fmax: those are libm calls without -ffast-math (NaN rules;
                // values are finite here), 21% of a time step's preparation.
                *dst++ = (uint16_t)(std::clamp(x, 0.0f, 1.0f) * kQuantScale + 0.5f);
              }
            }
          }
        }
  };
  const bool big = nb[2] >= 4 && v.voxelCount() >= (1u << 18);  // threads cost more than small volumes
  parallelRanges(nb[2], big ? 2 : 1, [&](long long z0, long long z1) { fill((int)z0, (int)z1); });
}

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
