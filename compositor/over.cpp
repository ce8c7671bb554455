#include "compositor/over.h"

#include <algorithm>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include "common/wire/pixels.h"

namespace tessera::compositor {
namespace {

// [0,1] floats to bytes, rounding to nearest: the same arithmetic as toRGBA8 (clamp, *255,
// +0.5, truncate), eight values per step where AVX2 is there.
void quantizeRow(const float* in, uint8_t* out, size_t n) {
  size_t i = 0;
#if defined(__AVX2__)
  const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), k255 = _mm256_set1_ps(255.0f),
               half = _mm256_set1_ps(0.5f);
  for (; i + 8 <= n; i += 8) {
    __m256 v = _mm256_min_ps(_mm256_max_ps(_mm256_loadu_ps(in + i), zero), one);
    __m256i q = _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(v, k255), half));
    __m128i q16 = _mm_packus_epi32(_mm256_castsi256_si128(q), _mm256_extracti128_si256(q, 1));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out + i), _mm_packus_epi16(q16, q16));
  }
#endif
  for (; i < n; ++i) out[i] = (uint8_t)(std::clamp(in[i], 0.0f, 1.0f) * 255.0f + 0.5f);
}

}  // namespace

uint64_t compositeRegion(const Rect& region, const std::vector<int>& order, const std::vector<proto::Piece>& pieces,
                         std::vector<float>& row, Image8& out) {
  row.resize(4 * (size_t)region.w);
  uint64_t active = 0;
  for (int y = region.y; y < region.y + region.h; ++y) {
    std::fill(row.begin(), row.end(), 0.0f);
    for (int b : order) {
      const proto::Piece& p = pieces[b];
      if (y >= p.active.y && y < p.active.y + p.active.h)
        compositeUnderRow(row.data(), region.x, p.pixels, p.active, y - p.active.y, p.format);
    }
    // Quantize once, at the end, so only one rounding reaches the image.
    uint8_t* d = out.at(region.x, y);
    quantizeRow(row.data(), d, row.size());
    for (int x = 0; x < region.w; ++x) active += d[4 * x + 3] != 0;
  }
  return active;
}

}  // namespace tessera::compositor
