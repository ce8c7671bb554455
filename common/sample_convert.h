// Samples as files store them (any voxel type, either byte order, scaled by a slope and an
// intercept) converted to the float values a volume holds: raw, NIfTI, NRRD and DICOM alike.
#pragma once
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cmath>
#include <cstring>
#include <string>

#include "common/volume.h"

namespace tessera::samples {

// The stored value of type T at p, in the file's byte order.
template <class T>
inline double stored(const unsigned char* p, bool big_endian) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return (double)v;
}

struct Scaling {
  double slope = 1, inter = 0;
  bool big_endian = false;
  // Subtracted in double before the value is rounded to float: float64 and 32-bit integer data,
  // or a header's intercept, can hold values whose spread is small next to their size (a
  // pressure of 101325 Pa varying by 1e-3), which float32 alone rounds to a few levels.
  double ref = 0;
};

template <class T>
inline void convert(const unsigned char* p, size_t count, const Scaling& s, float* out) {
  const bool scaled = s.slope != 1 || s.inter != 0;
  for (size_t i = 0; i < count; ++i) {
    const double v = stored<T>(p + i * sizeof(T), s.big_endian);
    out[i] = (float)((scaled ? s.slope * v + s.inter : v) - s.ref);
  }
}

// The first sample's value (after scaling), in double.
inline double firstValue(VoxelType type, const unsigned char* p, const Scaling& s) {
  double v = 0;
  switch (type) {
    case VoxelType::UInt8: v = stored<uint8_t>(p, s.big_endian); break;
    case VoxelType::Int8: v = stored<int8_t>(p, s.big_endian); break;
    case VoxelType::UInt16: v = stored<uint16_t>(p, s.big_endian); break;
    case VoxelType::Int16: v = stored<int16_t>(p, s.big_endian); break;
    case VoxelType::UInt32: v = stored<uint32_t>(p, s.big_endian); break;
    case VoxelType::Int32: v = stored<int32_t>(p, s.big_endian); break;
    case VoxelType::Float32: v = stored<float>(p, s.big_endian); break;
    case VoxelType::Float64: v = stored<double>(p, s.big_endian); break;
  }
  return s.slope != 1 || s.inter != 0 ? s.slope * v + s.inter : v;
}

inline void convertAll(VoxelType type, const unsigned char* p, size_t count, const Scaling& s, float* out) {
  switch (type) {
    case VoxelType::UInt8: return convert<uint8_t>(p, count, s, out);
    case VoxelType::Int8: return convert<int8_t>(p, count, s, out);
    case VoxelType::UInt16: return convert<uint16_t>(p, count, s, out);
    case VoxelType::Int16: return convert<int16_t>(p, count, s, out);
    case VoxelType::UInt32: return convert<uint32_t>(p, count, s, out);
    case VoxelType::Int32: return convert<int32_t>(p, count, s, out);
    case VoxelType::Float32: return convert<float>(p, count, s, out);
    case VoxelType::Float64: return convert<double>(p, count, s, out);
  }
}

// Why linear sample i of a file of `spec`, converted to x (not finite), is refused.
inline std::string nonFiniteProblem(const RawVolumeSpec& spec, size_t i, float x) {
  const size_t nx = spec.dims[0], ny = spec.dims[1];
  const std::string at = " at voxel (" + std::to_string(i % nx) + ", " + std::to_string(i / nx % ny) + ", " +
                         std::to_string(i / (nx * ny)) + "), linear index " + std::to_string(i);
  // A float64 sample, or one the header scales, can be finite and still overflow float32.
  const bool scaled = spec.slope != 1 || spec.inter != 0;
  if (std::isinf(x) && (spec.type == VoxelType::Float64 || scaled))
    return std::string(x > 0 ? "+" : "-") + "infinite or beyond float32's range (3.4e38)" +
           (scaled ? " after the header's scaling (slope " + std::to_string(spec.slope) + ", intercept " +
                         std::to_string(spec.inter) + ")"
                   : "") +
           at + "; Tessera holds samples as float32: rescale the data into its range";
  return "non-finite value " + std::to_string(x) + at +
         "; Tessera needs finite samples: replace NaN and infinities with a value outside the data's range (e.g. "
         "numpy.nan_to_num(v, nan=v_min)) and give range: to map it";
}

}  // namespace tessera::samples
