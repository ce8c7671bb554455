// Per-volume acceleration data built once and shared by every Raycaster of that volume:
// the min-max hierarchy and a uint16 copy of the normalised values (half the memory of
// float, and one 32-bit gather fetches the x-neighbour pair). Immutable; thread-safe.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "common/volume.h"
#include "renderer/minmax.h"

namespace tessera::renderer {

struct VolumeAccel {
  static constexpr float kQuantScale = 65535.0f;  // q = round(value * kQuantScale)

  explicit VolumeAccel(const Volume& v);
  // Returns the shared instance for this volume, building it on first use.
  static std::shared_ptr<const VolumeAccel> forVolume(const std::shared_ptr<const Volume>& v);

  MinMaxHierarchy hierarchy;
  // Same layout as Volume::values, plus padding so a pair read at the last voxel stays in bounds.
  std::vector<uint16_t> quantized;
};

}  // namespace tessera::renderer
