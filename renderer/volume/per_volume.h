// What casters of one volume share: one T per live volume (its bricked copy, its gradients),
// made by the first caster that asks and freed with the last holder. Casters of the same
// voxels with another colour map (the user's colour window) then cost only their
// classification.
#pragma once
#include <map>
#include <memory>
#include <mutex>
#include <utility>

#include "common/volume.h"

namespace tessera::renderer {

template <class T>
std::shared_ptr<const T> perVolume(const std::shared_ptr<const Volume>& v) {
  static std::mutex mu;
  static std::map<const Volume*, std::pair<std::weak_ptr<const Volume>, std::weak_ptr<const T>>> cache;
  std::lock_guard lock(mu);
  for (auto it = cache.begin(); it != cache.end();) {  // drop entries of freed volumes
    if (it->second.first.expired() || it->second.second.expired()) it = cache.erase(it);
    else ++it;
  }
  auto it = cache.find(v.get());
  if (it != cache.end() && it->second.first.lock() == v)
    if (auto a = it->second.second.lock()) return a;
  auto a = std::make_shared<const T>(*v);
  cache[v.get()] = {v, a};
  return a;
}

}  // namespace tessera::renderer
