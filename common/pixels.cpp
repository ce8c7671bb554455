#include "pixels.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace tessera {

uint16_t floatToHalf(float f) {
  uint32_t x;
  std::memcpy(&x, &f, 4);
  uint32_t sign = (x >> 16) & 0x8000u;
  uint32_t mant = x & 0x7FFFFFu;
  int exp = (int)((x >> 23) & 0xFF);
  if (exp == 0xFF) return (uint16_t)(sign | 0x7C00u | (mant ? 0x200u : 0u));  // Inf / NaN
  int e = exp - 127 + 15;
  if (e >= 0x1F) return (uint16_t)(sign | 0x7C00u);                           // overflow → Inf
  if (e <= 0) {                                                                // subnormal or zero
    if (e < -10) return (uint16_t)sign;
    mant |= 0x800000u;
    int shift = 14 - e;
    uint32_t half = mant >> shift, rest = mant & ((1u << shift) - 1), mid = 1u << (shift - 1);
    if (rest > mid || (rest == mid && (half & 1))) ++half;
    return (uint16_t)(sign | half);
  }
  uint32_t half = ((uint32_t)e << 10) | (mant >> 13), rest = mant & 0x1FFFu;
  if (rest > 0x1000u || (rest == 0x1000u && (half & 1))) ++half;  // carries into the exponent correctly
  return (uint16_t)(sign | half);
}

float halfToFloat(uint16_t h) {
  uint32_t sign = (uint32_t)(h & 0x8000u) << 16, exp = (h >> 10) & 0x1F, mant = h & 0x3FFu, x;
  if (exp == 0) {
    if (mant == 0) {
      x = sign;
    } else {  // subnormal: normalise
      int e = -1;
      do { mant <<= 1; ++e; } while (!(mant & 0x400u));
      x = sign | (uint32_t)(127 - 15 - e) << 23 | (mant & 0x3FFu) << 13;
    }
  } else if (exp == 0x1F) {
    x = sign | 0x7F800000u | mant << 13;
  } else {
    x = sign | (exp + 127 - 15) << 23 | mant << 13;
  }
  float f;
  std::memcpy(&f, &x, 4);
  return f;
}

std::vector<std::byte> packPixels(const ImageF& img, const Rect& r, proto::PixelFormat f) {
  size_t bpp = proto::bytesPerPixel(f), n = (size_t)r.area() * 4;
  std::vector<std::byte> out((size_t)r.area() * bpp);
  size_t i = 0;
  for (int y = r.y; y < r.y + r.h; ++y) {
    const float* row = img.at(r.x, y);
    for (int c = 0; c < r.w * 4; ++c, ++i) {
      float v = row[c];
      if (f == proto::PixelFormat::RGBA8) {
        out[i] = (std::byte)(uint8_t)std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f);
      } else if (f == proto::PixelFormat::RGBA16F) {
        uint16_t h = floatToHalf(v);
        out[2 * i] = (std::byte)(h & 0xFF);
        out[2 * i + 1] = (std::byte)(h >> 8);
      } else {
        std::memcpy(&out[4 * i], &v, 4);  // little-endian hosts only (checked at build time)
      }
    }
  }
  (void)n;
  return out;
}

void compositeUnder(ImageF& dst, const Rect& dst_rect, std::span<const std::byte> src, const Rect& src_rect,
                    proto::PixelFormat f) {
  const auto* b = reinterpret_cast<const uint8_t*>(src.data());
  size_t i = 0;
  float px[4];
  for (int y = 0; y < src_rect.h; ++y) {
    float* d = dst.at(src_rect.x - dst_rect.x, src_rect.y - dst_rect.y + y);
    for (int x = 0; x < src_rect.w; ++x, d += 4) {
      for (int c = 0; c < 4; ++c, ++i) {
        if (f == proto::PixelFormat::RGBA8) px[c] = b[i] * (1.0f / 255.0f);
        else if (f == proto::PixelFormat::RGBA16F) px[c] = halfToFloat((uint16_t)(b[2 * i] | b[2 * i + 1] << 8));
        else std::memcpy(&px[c], b + 4 * i, 4);
      }
      float t = 1.0f - d[3];
      for (int c = 0; c < 4; ++c) d[c] += t * px[c];
    }
  }
}

}  // namespace tessera
