#include "common/wire/row_filter.h"

#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

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

namespace {

constexpr size_t kStripHeaderBytes = 8;

// One strip's pixels, rgba interleaved -> four planes (and back): the header stays first.
void toPlanes(const uint8_t* in, uint8_t* out, size_t strip_bytes) {
  std::memcpy(out, in, kStripHeaderBytes);
  const size_t n = (strip_bytes - kStripHeaderBytes) / 4;
  const uint8_t* px = in + kStripHeaderBytes;
  uint8_t* r = out + kStripHeaderBytes;
  for (size_t i = 0; i < n; ++i) {
    r[i] = px[4 * i], r[n + i] = px[4 * i + 1], r[2 * n + i] = px[4 * i + 2], r[3 * n + i] = px[4 * i + 3];
  }
}

void fromPlanes(const uint8_t* in, uint8_t* out, size_t strip_bytes) {
  std::memcpy(out, in, kStripHeaderBytes);
  const size_t n = (strip_bytes - kStripHeaderBytes) / 4;
  const uint8_t* r = in + kStripHeaderBytes;
  uint8_t* px = out + kStripHeaderBytes;
  for (size_t i = 0; i < n; ++i) {
    px[4 * i] = r[i], px[4 * i + 1] = r[n + i], px[4 * i + 2] = r[2 * n + i], px[4 * i + 3] = r[3 * n + i];
  }
}

}  // namespace

void stripFilter(std::span<const std::byte> in, std::span<std::byte> out, size_t strip_bytes) {
  const auto* s = reinterpret_cast<const uint8_t*>(in.data());
  auto* d = reinterpret_cast<uint8_t*>(out.data());
  const size_t strips = strip_bytes ? in.size() / strip_bytes : 0;
  if (strips == 0) return;
  // Each strip's planes are made in a scratch strip and kept for the next one: out holds
  // only differences once written.
  thread_local std::vector<uint8_t> prev, cur;
  prev.resize(strip_bytes), cur.resize(strip_bytes);
  for (size_t k = 0; k < strips; ++k) {
    toPlanes(s + k * strip_bytes, cur.data(), strip_bytes);
    uint8_t* o = d + k * strip_bytes;
    if (k == 0) std::memcpy(o, cur.data(), strip_bytes);
    else for (size_t i = 0; i < strip_bytes; ++i) o[i] = (uint8_t)(cur[i] - prev[i]);
    std::swap(prev, cur);
  }
}

void stripUnfilter(std::span<std::byte> bytes, size_t strip_bytes) {
  auto* b = reinterpret_cast<uint8_t*>(bytes.data());
  const size_t strips = strip_bytes ? bytes.size() / strip_bytes : 0;
  if (strips == 0) return;
  upUnfilter(bytes.first(strips * strip_bytes), strip_bytes, 1);  // the planes of every strip, restored
  thread_local std::vector<uint8_t> planes;
  planes.resize(strip_bytes);
  for (size_t k = 0; k < strips; ++k) {
    uint8_t* strip = b + k * strip_bytes;
    std::memcpy(planes.data(), strip, strip_bytes);
    fromPlanes(planes.data(), strip, strip_bytes);
  }
}

}  // namespace tessera
