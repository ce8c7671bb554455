// Shared per-volume acceleration data (see volume_accel.h).
#include "renderer/volume_accel.h"

#include <cmath>
#include <map>
#include <mutex>

namespace tessera::renderer {

VolumeAccel::VolumeAccel(const Volume& v) : hierarchy(v), quantized(v.voxelCount() + 8, 0) {
  // Quantization error <= 0.5/65535 of the scalar: the table margin in TfTable::rangeIsEmpty
  // (2/4095) keeps empty-space decisions conservative for quantized samples.
  const size_t n = v.voxelCount();
  for (size_t i = 0; i < n; ++i) quantized[i] = (uint16_t)(std::fmin(std::fmax(v.values[i], 0.0f), 1.0f) * kQuantScale + 0.5f);
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
