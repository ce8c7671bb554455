// Private to fast_kernel.cpp: the fast kernel's empty-space leaper, which walks a ray over
// the min-max hierarchy's level-0 block grid and says how many samples it may leap over.
#pragma once
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "renderer/volume/kernels.h"

#ifndef TESSERA_KERNEL_ISA
#error "leaper.h is private to fast_kernel.cpp, which is compiled once per instruction set"
#endif

// In the instruction set's namespace: an inline function compiled with AVX-512 must never
// be the copy the linker keeps for the scalar kernel.
namespace tessera::renderer::TESSERA_KERNEL_ISA::fast {

// Skipped samples must lie this far (voxels) inside an empty node: float positions differ
// from the exact ones by < 1e-3 voxel for volumes up to 2048^3, so they stay inside.
inline constexpr double kSkipMargin = 1.0 / 64;
// The fewest samples the kernel takes between two leap decisions. Since the kernel passes over
// packets in empty cells at the cost of one gather, longer runs pay: 32 against 16, hollow
// shell 0.96x, head and Marschner-Lobb unlit 0.97x and 0.95x the time; 48 against 32, 0.97x,
// 0.95x and 0.97x; 64 and 96 no better than 48 (AMD EPYC, AVX-512).
inline constexpr int64_t kMinRun = 48;
inline constexpr double kInf = std::numeric_limits<double>::infinity();

// Three axes at once (lane 3 idle): GCC's vector types, so each instruction set's build gets
// its own code (SSE2 pairs for the scalar kernel). Every lane does the scalar arithmetic
// (a multiply, then an add: no contraction in these files), so the decisions are exact.
using V4d = double __attribute__((vector_size(32)));
using V4i = int32_t __attribute__((vector_size(16)));

// Empty-space leaps over the level-0 block grid, using the chessboard distance map.
// Double precision; samples are only leapt over when they lie kSkipMargin inside a cube of
// empty blocks, so their float positions (the kernel's) are inside it too.
struct Leaper {
  // Per axis (lane 3: a ray standing still at 0 in a grid of no blocks, so it never limits).
  V4d u0{}, du{}, inv{}, umax{}, nb{};
  V4i imax{};
  decltype(V4d{} < V4d{}) neg{}, fwd{}, moving{};  // lane masks
  int nbx = 0, nbxy = 0;
  int64_t block_run = 1;  // samples after which the ray has surely left any block
  const uint8_t* dist = nullptr;

  Leaper() = default;

  Leaper(const RaySpan& s, const Volume& v, const MinMaxHierarchy& h, const MinMaxHierarchy::Emptiness& e) {
    const auto d0 = h.dims(0);
    for (int a = 0; a < 3; ++a) {
      u0[a] = s.u0[a];
      du[a] = s.du[a];
      inv[a] = s.du[a] != 0 ? 1.0 / s.du[a] : 0.0;
      umax[a] = v.dims[a] - 1;
      imax[a] = std::max(0, v.dims[a] - 2);
      nb[a] = d0[a];
    }
    neg = du < 0.0;
    fwd = du > 0.0;
    moving = du != 0.0;
    nbx = d0[0];
    nbxy = d0[0] * d0[1];
    // A ray crosses a block's extent B along its fastest axis within B / max|du| samples.
    const double fastest = std::max({std::fabs(s.du[0]), std::fabs(s.du[1]), std::fabs(s.du[2])});
    block_run = (int64_t)std::min(1e9, std::ceil(MinMaxHierarchy::kBlock / fastest)) + 1;
    const int octant = (s.du[0] < 0 ? 1 : 0) | (s.du[1] < 0 ? 2 : 0) | (s.du[2] < 0 ? 4 : 0);
    dist = e.octant_distance[octant].data();
  }

  // Where the ray (from sample k, at u in block b) leaves the cube of r^3 blocks that starts
  // at b and extends forward (the ray's octant), shrunk by `margin`; `inside` tells whether
  // sample k itself is in the shrunk cube.
  double exit(const V4d& u, const V4d& b, double r, double margin, bool& inside) const {
    constexpr double B = MinMaxHierarchy::kBlock;
    const V4d inf = V4d{} + kInf;
    const V4d first = neg ? b - (r - 1) : b, last = neg ? b + 1.0 : b + r;
    const V4d lo = first <= 0.0 ? -inf : first * B + margin;
    const V4d hi = last >= nb ? inf : last * B - margin;
    const auto in = (u >= lo) & (u <= hi);
    inside = (in[0] & in[1] & in[2]) != 0;
    const V4d ea = moving ? ((fwd ? hi : lo) - u0) * inv : inf;
    return std::min(std::min(std::min(kInf, ea[0]), ea[1]), ea[2]);  // as the scalar loop: a NaN never wins
  }

  // Returns the first sample not leapt over (== k if sample k must be taken) and sets
  // run_end to a sample index where the ray has left k's block (the next decision point).
  int64_t step(int64_t k, int64_t k_end, int64_t& run_end) const {
    const V4d u = u0 + (double)k * du;
    V4d uc = u < 0.0 ? V4d{} : u;
    uc = umax < uc ? umax : uc;
    V4i i = __builtin_convertvector(uc, V4i);  // truncation, as (int)
    i = imax < i ? imax : i;
    constexpr int sh = std::countr_zero((unsigned)MinMaxHierarchy::kBlock);  // i >= 0: i / kBlock
    const V4i bi = i >> sh;
    const V4d b = __builtin_convertvector(bi, V4d);
    const int d = dist[bi[0] + nbx * bi[1] + nbxy * bi[2]];
    bool inside;
    if (d > 0) {
      const double e = std::min(exit(u, b, d, kSkipMargin, inside), (double)k_end);
      // Samples k..floor(e) lie inside the shrunk cube; double rounding of e (~1e-13 of a
      // step) is far below the margin, so the last of them is still safe to leap over.
      const int64_t next = std::min(k_end, (int64_t)e + 1);
      if (inside && next > k) return next;
    }
    // Sample k must be taken; the run has to reach past k's block. Runs are at least
    // kMinRun samples, so when a block takes fewer (coarse steps) its exact exit is moot.
    if (block_run <= kMinRun) {
      run_end = k + block_run;
    } else {
      const double e = std::min(exit(u, b, 1, 0.0, inside), (double)k_end);
      run_end = (int64_t)e + 1;
    }
    return k;
  }
};

}  // namespace tessera::renderer::TESSERA_KERNEL_ISA::fast
