// Samples as files store them (any voxel type, either byte order, scaled by a slope and an
// intercept) converted to the float values a volume holds: raw, NIfTI, NRRD and DICOM alike.
#pragma once
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

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
};

template <class T>
inline void convert(const unsigned char* p, size_t count, const Scaling& s, float* out) {
  const bool scaled = s.slope != 1 || s.inter != 0;
  for (size_t i = 0; i < count; ++i) {
    const double v = stored<T>(p + i * sizeof(T), s.big_endian);
    out[i] = (float)(scaled ? s.slope * v + s.inter : v);
  }
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

}  // namespace tessera::samples
