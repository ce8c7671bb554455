// Four float lanes in GCC's portable vector types (SSE2 on every x86-64, NEON elsewhere):
// for the passes over a time step's voxels that run on the renderers' cores while they
// render (reading, normalising, bricking), where scalar code with std::min/std::clamp
// compiles to a branch per voxel and GCC will not vectorize a float min/max reduction
// without -ffast-math. Lane arithmetic is IEEE like the scalar code's: results are identical.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstring>

namespace tessera::lanes {

typedef float F4 __attribute__((vector_size(16)));
typedef double D4 __attribute__((vector_size(32)));
typedef int32_t I4 __attribute__((vector_size(16)));
typedef uint16_t U4 __attribute__((vector_size(8)));

inline F4 load(const float* p) {
  F4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void store(float* p, F4 v) { std::memcpy(p, &v, sizeof v); }
inline F4 splat(float x) { return F4{x, x, x, x}; }

// -1 in the lanes holding NaN or an infinity (exponent all ones), else 0.
inline I4 nonFinite(F4 x) {
  I4 bits;
  std::memcpy(&bits, &x, sizeof bits);
  return (bits & 0x7f800000) == 0x7f800000;
}

// Lane-wise minimum and maximum, with std::min/std::max's operand order.
inline F4 min(F4 a, F4 x) { return x < a ? x : a; }
inline F4 max(F4 a, F4 x) { return a < x ? x : a; }

inline float hmin(F4 v) { return std::min(std::min(v[0], v[1]), std::min(v[2], v[3])); }
inline float hmax(F4 v) { return std::max(std::max(v[0], v[1]), std::max(v[2], v[3])); }
inline bool any(I4 m) { return (m[0] | m[1] | m[2] | m[3]) != 0; }

}  // namespace tessera::lanes
