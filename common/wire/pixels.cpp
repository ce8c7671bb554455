#include "common/wire/pixels.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/cpu.h"

#if defined(__x86_64__)
#include <immintrin.h>
// F16C, AVX2 and SSSE3 are in every x86-64-v3 CPU; these run where cpuIsa() says so.
#define TESSERA_V3 __attribute__((target("avx2,f16c,fma")))
#endif

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

// RGBA16F pieces travel as two byte planes: the low bytes of every half, then the high
// bytes. The high bytes (sign, exponent, top of the mantissa) are smooth and compress
// well; interleaved with the noisy low bytes they would not (LZ4: 35% of raw against 47%).
// F16C converts 8 floats per instruction (bit-identical to floatToHalf for every non-NaN).
#if defined(__x86_64__)
TESSERA_V3 static size_t floatsToHalfPlanesF16c(const float* in, uint8_t* lo, uint8_t* hi, size_t n) {
  // Eight halves -> their eight low bytes, then their eight high bytes, in one shuffle.
  const __m128i split = _mm_setr_epi8(0, 2, 4, 6, 8, 10, 12, 14, 1, 3, 5, 7, 9, 11, 13, 15);
  size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    __m128i h = _mm256_cvtps_ph(_mm256_loadu_ps(in + i), _MM_FROUND_TO_NEAREST_INT);
    __m128i planes = _mm_shuffle_epi8(h, split);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(lo + i), planes);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(hi + i), _mm_unpackhi_epi64(planes, planes));
  }
  return i;
}
#endif

static void floatsToHalfPlanes(const float* in, uint8_t* lo, uint8_t* hi, size_t n) {
  size_t i = 0;
#if defined(__x86_64__)
  if (cpuIsa() >= Isa::Avx2) i = floatsToHalfPlanesF16c(in, lo, hi, n);
#endif
  for (; i < n; ++i) {
    uint16_t h1 = floatToHalf(in[i]);
    lo[i] = (uint8_t)(h1 & 0xFF);
    hi[i] = (uint8_t)(h1 >> 8);
  }
}

// "Under" of one row of rgba16f planes; F16C widens four halves per instruction.
#if defined(__x86_64__)
TESSERA_V3 static void compositeHalfRowF16c(float* d, const uint8_t* lo, const uint8_t* hi, int w) {
  for (int x = 0; x < w; ++x, d += 4, lo += 4, hi += 4) {
    float px[4];
    uint32_t l, h;
    std::memcpy(&l, lo, 4);
    std::memcpy(&h, hi, 4);
    _mm_storeu_ps(px, _mm_cvtph_ps(_mm_unpacklo_epi8(_mm_cvtsi32_si128((int)l), _mm_cvtsi32_si128((int)h))));
    const float t = 1.0f - d[3];
    for (int c = 0; c < 4; ++c) d[c] += t * px[c];
  }
}
#endif

static void compositeHalfRow(float* d, const uint8_t* lo, const uint8_t* hi, int w) {
#if defined(__x86_64__)
  if (cpuIsa() >= Isa::Avx2) return compositeHalfRowF16c(d, lo, hi, w);
#endif
  for (int x = 0; x < w; ++x, d += 4, lo += 4, hi += 4) {
    float px[4];
    for (int c = 0; c < 4; ++c) px[c] = halfToFloat((uint16_t)(lo[c] | hi[c] << 8));
    const float t = 1.0f - d[3];
    for (int c = 0; c < 4; ++c) d[c] += t * px[c];
  }
}

std::vector<std::byte> packPixels(const ImageF& img, const Rect& r, proto::PixelFormat f) {
  std::vector<std::byte> out;
  packPixels(img, r, f, out);
  return out;
}

void packPixels(const ImageF& img, const Rect& r, proto::PixelFormat f, std::vector<std::byte>& out) {
  const size_t bpp = proto::bytesPerPixel(f), row_values = (size_t)r.w * 4, values = (size_t)r.area() * 4;
  out.resize((size_t)r.area() * bpp);
  auto* o = reinterpret_cast<uint8_t*>(out.data());
  for (int y = r.y; y < r.y + r.h; ++y) {
    const float* row = img.at(r.x, y);
    size_t first = (size_t)(y - r.y) * row_values;  // index of this row's first value
    if (f == proto::PixelFormat::RGBA8) {
      quantizeToUnorm8(row, o + first, row_values);
    } else if (f == proto::PixelFormat::RGBA16F) {
      floatsToHalfPlanes(row, o + first, o + values + first, row_values);
    } else {
      std::memcpy(o + 4 * first, row, row_values * 4);
    }
  }
}

TESSERA_CLONES void compositeUnderRow(float* d, int dst_x, std::span<const std::byte> src, const Rect& src_rect, int row,
                       proto::PixelFormat f) {
  const auto* b = reinterpret_cast<const uint8_t*>(src.data());
  const size_t values = (size_t)src_rect.area() * 4, first = (size_t)row * src_rect.w * 4;
  d += 4 * (size_t)(src_rect.x - dst_x);
  const int w = src_rect.w;
  // One loop per format so each stays simple enough for the vectorizer.
  if (f == proto::PixelFormat::RGBA8) {
    const uint8_t* s = b + first;
    for (int x = 0; x < w; ++x, d += 4, s += 4) {
      const float t = (1.0f - d[3]) * (1.0f / 255.0f);
      for (int c = 0; c < 4; ++c) d[c] += t * s[c];
    }
  } else if (f == proto::PixelFormat::RGBA16F) {
    compositeHalfRow(d, b + first, b + values + first, w);
  } else {
    const uint8_t* s = b + 4 * first;
    for (int x = 0; x < w; ++x, d += 4, s += 16) {
      float px[4];
      std::memcpy(px, s, 16);
      const float t = 1.0f - d[3];
      for (int c = 0; c < 4; ++c) d[c] += t * px[c];
    }
  }
}

void compositeUnder(ImageF& dst, const Rect& dst_rect, std::span<const std::byte> src, const Rect& src_rect,
                    proto::PixelFormat f) {
  for (int y = 0; y < src_rect.h; ++y)
    compositeUnderRow(dst.at(0, src_rect.y - dst_rect.y + y), dst_rect.x, src, src_rect, y, f);
}

void compositeMaximumRow(float* d, int dst_x, std::span<const std::byte> src, const Rect& src_rect, int row,
                         proto::PixelFormat f) {
  const auto* b = reinterpret_cast<const uint8_t*>(src.data());
  const size_t values = (size_t)src_rect.area() * 4, first = (size_t)row * src_rect.w * 4;
  d += 4 * (size_t)(src_rect.x - dst_x);
  for (size_t i = 0; i < 4 * (size_t)src_rect.w; ++i) {
    float v;
    if (f == proto::PixelFormat::RGBA8) v = b[first + i] * (1.0f / 255.0f);
    else if (f == proto::PixelFormat::RGBA16F) v = halfToFloat((uint16_t)(b[first + i] | b[values + first + i] << 8));
    else std::memcpy(&v, b + 4 * (first + i), 4);
    d[i] = std::max(d[i], v);
  }
}

void compositeMaximum(ImageF& dst, const Rect& dst_rect, std::span<const std::byte> src, const Rect& src_rect,
                      proto::PixelFormat f) {
  for (int y = 0; y < src_rect.h; ++y)
    compositeMaximumRow(dst.at(0, src_rect.y - dst_rect.y + y), dst_rect.x, src, src_rect, y, f);
}

}  // namespace tessera
