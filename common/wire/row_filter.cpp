#include "common/wire/row_filter.h"

#include <cstdint>
#include <cstring>

namespace tessera {

namespace {

size_t rowsPerPlane(size_t bytes, size_t row_bytes, size_t planes) {
  return row_bytes && planes ? bytes / (row_bytes * planes) : 0;
}

}  // namespace

void upFilter(std::span<const std::byte> in, std::span<std::byte> out, size_t row_bytes, size_t planes) {
  const auto* s = reinterpret_cast<const uint8_t*>(in.data());
  auto* d = reinterpret_cast<uint8_t*>(out.data());
  const size_t rows = rowsPerPlane(in.size(), row_bytes, planes);
  for (size_t p = 0; p < planes; ++p) {
    const size_t plane = p * rows * row_bytes;
    if (rows) std::memcpy(d + plane, s + plane, row_bytes);
    for (size_t r = 1; r < rows; ++r) {
      const uint8_t* cur = s + plane + r * row_bytes;
      const uint8_t* up = cur - row_bytes;
      uint8_t* o = d + plane + r * row_bytes;
      for (size_t i = 0; i < row_bytes; ++i) o[i] = (uint8_t)(cur[i] - up[i]);
    }
  }
}

void upUnfilter(std::span<std::byte> bytes, size_t row_bytes, size_t planes) {
  auto* b = reinterpret_cast<uint8_t*>(bytes.data());
  const size_t rows = rowsPerPlane(bytes.size(), row_bytes, planes);
  for (size_t p = 0; p < planes; ++p) {
    uint8_t* plane = b + p * rows * row_bytes;
    for (size_t r = 1; r < rows; ++r) {
      uint8_t* cur = plane + r * row_bytes;
      const uint8_t* up = cur - row_bytes;
      for (size_t i = 0; i < row_bytes; ++i) cur[i] = (uint8_t)(cur[i] + up[i]);
    }
  }
}

}  // namespace tessera
