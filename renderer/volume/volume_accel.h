// Per-volume acceleration data built once and shared by every Raycaster of that volume:
// the min-max hierarchy and a bricked uint16 copy of the normalised values: 8^3-cell
// bricks with their +1 apron (9^3 voxels), so the eight corners of any sample lie in one
// brick at fixed offsets (+1, +9, +81) and a ray's samples stay within few cache lines;
// one 32-bit read fetches an x-neighbour pair. Both come from one pass over the values
// (a brick's 9^3 voxels are exactly what its hierarchy block ranges over), which also finds
// non-finite values: a time step is prepared with one read of its samples. Immutable;
// thread-safe.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "common/volume.h"
#include "renderer/volume/minmax.h"

namespace tessera::renderer {

// Leaves new elements uninitialised: the bricked copy is written whole by its one pass, so
// zeroing it first would be one more pass over a time step's memory.
template <class T>
struct UninitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitAllocator<U>;
  };
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

struct VolumeAccel {
  static constexpr float kQuantScale = 65535.0f;  // q = round(value * kQuantScale)

  explicit VolumeAccel(const Volume& v);
  // Leaves its bricked copy to the next one built (see volume_accel.cpp).
  ~VolumeAccel();
  VolumeAccel(const VolumeAccel&) = delete;
  VolumeAccel& operator=(const VolumeAccel&) = delete;
  // Returns the shared instance for this volume, building it on first use.
  static std::shared_ptr<const VolumeAccel> forVolume(const std::shared_ptr<const Volume>& v);

  MinMaxHierarchy hierarchy;
  static constexpr int kEdge = MinMaxHierarchy::kBlock + 1;        // voxels per brick edge
  static constexpr int kBrickSize = kEdge * kEdge * kEdge;        // 729
  // Brick (bx,by,bz) (the hierarchy's level-0 blocks) starts at
  // kBrickSize * (bx + nb[0] * (by + nb[1] * bz)); voxel (lx,ly,lz) inside at lx + 9*(ly + 9*lz).
  std::vector<uint16_t, UninitAllocator<uint16_t>> bricked;  // + 8 zeros: reads past the last brick
  std::array<int, 3> nb{1, 1, 1};
  bool all_finite = true;  // false: some value is NaN or infinite (its bricked value is meaningless)

 private:
  struct Pass;  // the bricked copy and level 0 of the hierarchy, from one pass
  explicit VolumeAccel(Pass&& p);
};

}  // namespace tessera::renderer
