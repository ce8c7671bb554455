// Shared per-volume acceleration data (see volume_accel.h).
#include "renderer/volume/volume_accel.h"

#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <mutex>
#include <thread>
#include <utility>
#include <algorithm>

#include "common/lanes.h"
#include "common/parallel.h"
#include "renderer/volume/per_volume.h"

namespace tessera::renderer {

struct VolumeAccel::Pass {
  std::array<int, 3> nb;
  decltype(VolumeAccel::bricked) bricked;
  std::vector<float> mn, mx;
  bool all_finite = true;
};

namespace {

using lanes::F4;
using lanes::I4;
using lanes::U4;

// (uint16_t)(std::clamp(x, 0, 1) * kQuantScale + 0.5f) for every finite x; NaN maps to 0
// (converting it to an integer would be undefined; its volume is refused anyway).
uint16_t quantize(float x) { return (uint16_t)((x > 0 ? (x < 1 ? x : 1) : 0) * VolumeAccel::kQuantScale + 0.5f); }

void quantize4(F4 x, uint16_t* dst) {
  const F4 zero = lanes::splat(0), one = lanes::splat(1);
  x = x > zero ? (x < one ? x : one) : zero;
  const U4 q = __builtin_convertvector(__builtin_convertvector(x * VolumeAccel::kQuantScale + 0.5f, I4), U4);
  std::memcpy(dst, &q, sizeof q);
}

// One brick: its 9^3 voxels (clamped at the far borders) quantized into `dst`, their range
// into mn/mx. Returns false if one is not finite. Rows are 9 voxels: two vectors and one more
// (scalar code with std::clamp's branches took 1.7 ns a voxel, twice this).
bool fillBrick(const Volume& v, int bx, int by, int bz, uint16_t* dst, float& mn, float& mx) {
  constexpr int B = MinMaxHierarchy::kBlock, E = VolumeAccel::kEdge;
  static_assert(B == 8, "a brick row is two vectors of four and one voxel");
  const int x0 = bx * B, inside = std::min(E, v.dims[0] - x0);  // voxels of a row in the volume
  float row[E];
  const float first = v.values[v.index(x0, std::min(by * B, v.dims[1] - 1), std::min(bz * B, v.dims[2] - 1))];
  F4 lo = {first, first, first, first}, hi = lo;
  float lo_last = first, hi_last = first;
  I4 bad = {0, 0, 0, 0};
  for (int lz = 0; lz < E; ++lz) {
    const int z = std::min(bz * B + lz, v.dims[2] - 1);
    for (int ly = 0; ly < E; ++ly) {
      const float* src = &v.values[v.index(x0, std::min(by * B + ly, v.dims[1] - 1), z)];
      if (inside < E) {  // the far border: the last voxel repeats
        for (int lx = 0; lx < E; ++lx) row[lx] = src[std::min(lx, inside - 1)];
        src = row;
      }
      for (int h = 0; h < B; h += 4) {
        const F4 x = lanes::load(src + h);
        bad |= lanes::nonFinite(x);
        lo = lanes::min(lo, x);
        hi = lanes::max(hi, x);
        quantize4(x, dst + h);
      }
      const float x = src[B];
      bad |= lanes::nonFinite(lanes::splat(x));
      lo_last = std::min(lo_last, x), hi_last = std::max(hi_last, x);
      dst[B] = quantize(x);
      dst += E;
    }
  }
  mn = std::min(lanes::hmin(lo), lo_last), mx = std::max(lanes::hmax(hi), hi_last);
  return !lanes::any(bad);
}

// The bricked copy of the last time step freed, for the next step's: a playing renderer
// builds one a step, and fresh memory costs a page fault and the kernel's zeroing per 4 KiB
// (measured ~2% of a playing farm's cycles). At most one is kept.
std::mutex spare_mu;
decltype(VolumeAccel::bricked) spare_bricks;

// The spare, if it is not more than twice the size wanted (a smaller volume's steps should
// not keep a larger one's memory); empty, so growing it copies nothing.
decltype(VolumeAccel::bricked) takeSpareBricks(size_t wanted) {
  std::lock_guard lock(spare_mu);
  auto spare = std::exchange(spare_bricks, {});
  if (spare.capacity() > 2 * wanted) return {};
  spare.clear();
  return spare;
}

}  // namespace

VolumeAccel::~VolumeAccel() {
  std::lock_guard lock(spare_mu);
  if (bricked.capacity() > spare_bricks.capacity()) spare_bricks = std::move(bricked);
}

VolumeAccel::VolumeAccel(const Volume& v) : VolumeAccel([&v] {
  // Quantization error <= 0.5/65535 of the scalar: the table margin in TfTable::rangeIsEmpty
  // (2/4095) keeps empty-space decisions conservative for quantized samples.
  if (v.values.size() != v.voxelCount() || v.voxelCount() == 0)
    throw std::invalid_argument("VolumeAccel: volume has no voxels or wrong value count");
  Pass p;
  p.nb = MinMaxHierarchy::blockDims(v.dims);
  const size_t blocks = (size_t)p.nb[0] * p.nb[1] * p.nb[2];
  p.bricked = takeSpareBricks((size_t)kBrickSize * blocks + 8);
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
  return perVolume<VolumeAccel>(v);
}

}  // namespace tessera::renderer
